//! Processor-in-the-loop: the control core on an emulated Cortex-M4F (QEMU `mps2-an386`),
//! stepped through recorded bus traffic, reporting what it sends and what each step cost.
//!
//! The image links with its own linker script, `an386.x`: the AN386's 4 MiB ZBT SSRAM1 at
//! 0x0000_0000 for code, 128 KiB — the STM32G474's RAM size — of ZBT SSRAM2/3 at 0x2000_0000
//! for data and stack. `cargo xtask pil` turns the committed recording into the input file
//! embedded here (`PIL_INPUTS`, in `pil-format`'s raw format), builds, runs QEMU with
//! `-icount shift=0` and compares the frames with the host build's. Each tick the firmware's
//! one service loop ([`firmware::node::service`], as on the board) gives the
//! [`firmware::Node`] the frames recorded for it and runs the tick, through a port over the
//! recording; the image times both with SysTick, then prints (semihosting):
//!
//! ```text
//! PIL-CAL <instructions> <systick ticks>   a calibration loop of known length
//! PIL-BASE <systick ticks>                 the cost of reading the timer twice
//! T <tick> <systick ticks>                 one control step: frames in, step, frames out
//! F <id hex> <data hex>                    each frame the step sent
//! PIL-STACK <bytes>                        peak stack (cortex-m-rt paints it at reset)
//! PIL-END <ticks>
//! ```
// Functions stay short enough to read whole (clippy.toml: 80 lines); tests may run longer.
#![cfg_attr(not(test), warn(clippy::too_many_lines))]
#![cfg_attr(target_os = "none", no_std, no_main)]
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing
)]

#[cfg(target_os = "none")]
mod image;
#[cfg(target_os = "none")]
mod inputs;
#[cfg(target_os = "none")]
mod line;
#[cfg(target_os = "none")]
mod recorded;

#[cfg(not(target_os = "none"))]
fn main() {
    println!("firmware-pil is the processor-in-the-loop image: run it with `cargo xtask pil`");
}
