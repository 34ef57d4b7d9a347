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

/// The committed recording, refused when a frame of it does not decode under this build's
/// wire contract: a recording made before a layout changed would feed both builds frames they
/// reject, and their agreement would show nothing.
fn load_recording() -> Result<Recording, String> {
    let path = root().join(RECORDING);
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let recording = Recording::from_compact(&bytes).map_err(|e| {
        format!(
            "{}: {e} (regenerate: cargo xtask pil --record)",
            path.display()
        )
    })?;
    stale_frame(&recording).map_or(Ok(recording), |(tick, id, error)| {
        Err(format!(
            "{}: tick {tick}, frame 0x{id:03X} does not decode under wire version {}: {error:?} \
             (the recording predates a change of the wire contract; regenerate: cargo xtask pil \
             --record)",
            path.display(),
            protocol::WIRE_VERSION
        ))
    })
}

/// The first frame of `recording` this build's protocol refuses to decode: its tick, its
/// identifier and why.
fn stale_frame(recording: &Recording) -> Option<(usize, u16, protocol::DecodeError)> {
    recording
        .ticks
        .iter()
        .enumerate()
        .find_map(|(tick, frames)| {
            frames.iter().find_map(|(id, data)| {
                protocol::decode_frame(*id, data)
                    .err()
                    .map(|error| (tick, *id, error))
            })
        })
}

#[cfg(test)]
mod stale_tests {
    use super::*;

    #[test]
    fn a_frame_of_another_layout_marks_the_recording_stale() {
        // A 12-byte operator command: wire version 7's layout, 16 bytes since version 8.
        let recording = Recording {
            control_hz: 250,
            first_tick: 0,
            ticks: vec![vec![], vec![(0x200, vec![0; 12])]],
        };
        let (tick, id, _) = stale_frame(&recording).unwrap();
        assert_eq!((tick, id), (1, 0x200));
        let fresh = Recording {
            ticks: vec![vec![]],
            ..recording
        };
        assert!(stale_frame(&fresh).is_none());
    }
}
