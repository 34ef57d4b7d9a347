//! `cargo xtask pil [--record]`: processor-in-the-loop on an emulated Cortex-M4F.
//!
//! The control core (`firmware/pil`, the same `Node` and service loop,
//! `firmware::node::service`, as the STM32 image) runs in QEMU's `mps2-an386` with
//! `-icount shift=0` against the frames the firmware received in a recorded closed-loop run (`firmware/pil/recording.pil`), and this task checks
//! that every frame it sends equals, field by field, what the host build of the core sends for
//! the same inputs (fixed-point fields within one count: the float maths may round differently;
//! enumerations, flags and counters exactly). It prints the instructions per control step
//! (SysTick at QEMU's 25 MHz processor clock; with `-icount shift=0` one instruction takes 1 ns,
//! so one tick is 40 instructions — calibrated on every run with a loop of known length) and
//! the peak stack (cortex-m-rt paints the stack at reset; the image finds the high-water mark).
//!
//! The image links with its own linker script, `firmware/pil/an386.x` (code in ZBT SSRAM1 at
//! 0x0000_0000, 4 MiB; data and stack in ZBT SSRAM2/3 at 0x2000_0000, limited to the
//! STM32G474's 128 KiB so that the image fits the board's RAM too). The recording's formats —
//! the compact one committed, the raw one the image embeds — are the `pil-format` crate's.
//!
//! `--record` first reruns the closed loop (`sim-host` example `pil_record`: stand, trot
//! forward, fold onto the wheels and drive off balancing) and rewrites the recording.
//!
//! | module | what it does |
//! |---|---|
//! | [`image`] | the input file from the recording, the build of the image |
//! | [`qemu`] | running the image in QEMU and reading what it printed |
//! | [`compare`] | the host build on the same inputs, frame by frame against the image's |
//! | [`report`] | the `MEASURED` lines and the budgets |
//! | [`record`] | `--record` |

mod compare;
mod image;
mod qemu;
mod record;
mod report;

pub use image::prepare_build_env;
use pil_format::Recording;

use crate::util::root;

/// The committed recording, relative to the workspace root.
const RECORDING: &str = "firmware/pil/recording.pil";

/// Frames one control step received or sent: id and data.
pub type Frames = Vec<pil_format::Frame>;

pub fn run(args: &[String]) -> Result<(), String> {
    if args.iter().any(|a| a == "--record") {
        record::run()?;
    } else if let Some(other) = args.first() {
        return Err(format!("unknown option `{other}` (use --record)"));
    }
    crate::setup::ensure_target()?;
    crate::apt::ensure(
        &["qemu-system-arm"],
        "the processor-in-the-loop test (cargo xtask pil)",
    )?;
    let recording = load_recording()?;
    let image = image::build(&recording)?;
    let pil = qemu::PilRun::parse(&qemu::run(&image)?)?;
    let host = compare::host_replay(&recording)?;
    let check = compare::compare(&host, &pil.ticks)?;
    report::print(&recording, &pil, &check)
}

/// The committed recording's frames, tick by tick (the fuzz seeds come from them).
pub fn recorded_ticks() -> Result<Vec<Frames>, String> {
    Ok(load_recording()?.ticks)
}

/// The committed recording.
fn load_recording() -> Result<Recording, String> {
    let path = root().join(RECORDING);
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Recording::from_compact(&bytes).map_err(|e| {
        format!(
            "{}: {e} (regenerate: cargo xtask pil --record)",
            path.display()
        )
    })
}
