//! The control core as a microcontroller image for an STM32G474 (Cortex-M4F, 512 KiB flash,
//! 128 KiB RAM, FDCAN), e.g. a NUCLEO-G474RE with a CAN FD transceiver on PA11 (RX) / PA12 (TX).
//!
//! One loop, no interrupts, the firmware's one service loop ([`firmware::node::service`]): every
//! frame the FDCAN received goes into the [`firmware::Node`] at the current tick
//! ([`firmware::node::service::receive`]); when the control timer (SysTick,
//! [`timer::ControlTimer`], good for 1 kHz and more) says a tick is due, the node runs it and its
//! frames go out ([`firmware::node::service::transmit`]). The FDCAN driver is `stm32g4xx-hal`
//! with the `fdcan` crate; [`port`] is the thin adapter between it and `embedded_can::nb::Can`,
//! which is all the core sees of the bus.
//!
//! Build, size and flash: `cargo xtask firmware`; `cargo run --profile mcu -p firmware-stm32
//! --target thumbv7em-none-eabihf` flashes a board through probe-rs (`.cargo/config.toml`).
//! On the host this package is a stub that says so.
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
mod board;
#[cfg(target_os = "none")]
mod flash;
#[cfg(target_os = "none")]
mod port;
#[cfg(target_os = "none")]
mod timer;

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "firmware-stm32 is the STM32G474 image: build it with `cargo xtask firmware`, flash it \
         with `cargo run --release -p firmware-stm32 --target thumbv7em-none-eabihf`"
    );
}
