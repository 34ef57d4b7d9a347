//! `cargo xtask pil [--record]`: processor-in-the-loop on an emulated Cortex-M4F.
//!
//! The control core (`firmware/pil`, the same `Node` and `firmware::node::service` glue as the STM32
//! image) runs in QEMU's `mps2-an386` with `-icount shift=0` against the frames the firmware
//! received in a recorded closed-loop run (`firmware/pil/recording.pil`), and this task checks
//! that every frame it sends equals, field by field, what the host build of the core sends for
//! the same inputs (fixed-point fields within one count: the float maths may round differently;
//! enumerations, flags and counters exactly). It prints the instructions per control step
//! (SysTick at QEMU's 25 MHz processor clock; with `-icount shift=0` one instruction takes 1 ns,
//! so one tick is 40 instructions — calibrated on every run with a loop of known length) and
//! the peak stack (cortex-m-rt paints the stack at reset; the image finds the high-water mark).
//!
//! The image links with a linker script generated here for the AN386 (code in ZBT SSRAM1 at
//! 0x0000_0000, 4 MiB; data and stack in ZBT SSRAM2/3 at 0x2000_0000, limited to the
//! STM32G474's 128 KiB so that the image fits the board's RAM too) — a complete script rather
//! than a `memory.x` for cortex-m-rt's `link.x`, because the linker finds the board's `memory.x`
//! in the workspace root before any other.
//!
//! `--record` first reruns the closed loop (`sim-host` example `pil_record`: stand, trot
//! forward, fold onto the wheels and drive off balancing) and rewrites the recording.

use std::io::Read;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use firmware::{Config, Node, Tick, TickRate};
use protocol::signal::{Field, WireType};
use protocol::MessageId;

use crate::setup::MCU_TARGET;
use crate::util::{cargo, root, run as sh};

/// The committed recording, relative to the workspace root.
const RECORDING: &str = "firmware/pil/recording.pil";
/// Seconds of closed loop `--record` captures.
const RECORD_SECONDS: &str = "6";
/// QEMU gets this long.
const QEMU_TIMEOUT: Duration = Duration::from_secs(300);
/// Goals: instructions per control step, peak stack bytes.
const INSTRUCTION_BUDGET: u64 = 20_000;
const STACK_BUDGET: u64 = 8 * 1024;
/// Data RAM of the PIL image: the STM32G474's.
const RAM_KIB: u32 = 128;
/// Code memory: the AN386's ZBT SSRAM1.
const CODE_KIB: u32 = 4 * 1024;

pub fn run(args: &[String]) -> Result<(), String> {
    if args.iter().any(|a| a == "--record") {
        record()?;
    } else if let Some(other) = args.first() {
        return Err(format!("unknown option `{other}` (use --record)"));
    }
    crate::setup::ensure_target()?;
    crate::apt::ensure(
        &["qemu-system-arm"],
        "the processor-in-the-loop test (cargo xtask pil)",
    )?;
    let path = root().join(RECORDING);
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let recording = Recording::from_compact(&bytes).map_err(|e| {
        format!(
            "{}: {e} (regenerate: cargo xtask pil --record)",
            path.display()
        )
    })?;
    let dir = work_dir()?;
    let link = dir.join("pil.x");
    let inputs = dir.join("inputs.raw");
    write(&link, link_script().as_bytes())?;
    write(&inputs, &recording.to_raw())?;
    sh(cargo()
        .args([
            "build",
            "--profile",
            crate::firmware::PROFILE,
            "-p",
            "firmware-pil",
            "--target",
            MCU_TARGET,
        ])
        .env("PIL_LINK_X", &link)
        .env("PIL_INPUTS", &inputs))?;
    let image = crate::firmware::image("firmware-pil");
    let text = qemu(&image)?;
    let pil = PilRun::parse(&text)?;
    let host = host_replay(&recording)?;
    let check = compare(&host, &pil.ticks)?;
    report(&recording, &pil, &check)
}

/// Environment for building the PIL image outside this task (e.g. clippy): the generated files.
pub fn prepare_build_env() -> Result<Vec<(&'static str, PathBuf)>, String> {
    let path = root().join(RECORDING);
    let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let recording =
        Recording::from_compact(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let dir = work_dir()?;
    let link = dir.join("pil.x");
    let inputs = dir.join("inputs.raw");
    write(&link, link_script().as_bytes())?;
    write(&inputs, &recording.to_raw())?;
    Ok(vec![("PIL_LINK_X", link), ("PIL_INPUTS", inputs)])
}

fn work_dir() -> Result<PathBuf, String> {
    let dir = root().join("target").join("pil");
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    Ok(dir)
}

fn write(path: &std::path::Path, bytes: &[u8]) -> Result<(), String> {
    // Unchanged files keep their time stamps, so cargo does not rebuild for nothing.
    if std::fs::read(path).ok().as_deref() == Some(bytes) {
        return Ok(());
    }
    std::fs::write(path, bytes).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The PIL image's linker script for cortex-m-rt on the AN386: the memory map, the vector table
/// first at 0x0000_0000 (where the M4 fetches its initial stack pointer and reset vector), code
/// and read-only data in SSRAM1, `.data` (copied from its load image), `.bss` and the stack in
/// SSRAM2/3, and the symbols cortex-m-rt's start-up code uses.
fn link_script() -> String {
    format!(
        "/* Generated by `cargo xtask pil`: QEMU mps2-an386 (Cortex-M4F). */
MEMORY
{{
  CODE : ORIGIN = 0x00000000, LENGTH = {CODE_KIB}K
  RAM  : ORIGIN = 0x20000000, LENGTH = {RAM_KIB}K
}}

ENTRY(Reset);
EXTERN(__RESET_VECTOR);
EXTERN(__EXCEPTIONS);
EXTERN(__INTERRUPTS);
EXTERN(DefaultHandler);

PROVIDE(NonMaskableInt = DefaultHandler);
PROVIDE(MemoryManagement = DefaultHandler);
PROVIDE(BusFault = DefaultHandler);
PROVIDE(UsageFault = DefaultHandler);
PROVIDE(SecureFault = DefaultHandler);
PROVIDE(SVCall = DefaultHandler);
PROVIDE(DebugMonitor = DefaultHandler);
PROVIDE(PendSV = DefaultHandler);
PROVIDE(SysTick = DefaultHandler);
PROVIDE(DefaultHandler = DefaultHandler_);
PROVIDE(HardFault = HardFault_);
PROVIDE(__pre_init = DefaultPreInit);

_ram_start = ORIGIN(RAM);
_ram_end = ORIGIN(RAM) + LENGTH(RAM);
_stack_start = _ram_end;

SECTIONS
{{
  .vector_table ORIGIN(CODE) :
  {{
    __vector_table = .;
    LONG(_stack_start & 0xFFFFFFF8);
    KEEP(*(.vector_table.reset_vector));
    __exceptions = .;
    KEEP(*(.vector_table.exceptions));
    __eexceptions = .;
    KEEP(*(.vector_table.interrupts));
  }} > CODE

  .text : ALIGN(4)
  {{
    __stext = .;
    *(.PreResetTrampoline);
    *(.Reset);
    *(.text .text.*);
    *(.HardFaultTrampoline);
    *(.HardFault.*);
    . = ALIGN(4);
    __etext = .;
  }} > CODE

  .rodata : ALIGN(4)
  {{
    *(.rodata .rodata.*);
    . = ALIGN(4);
  }} > CODE

  .data : ALIGN(4)
  {{
    __sdata = .;
    *(.data .data.*);
    . = ALIGN(4);
    __edata = .;
  }} > RAM AT > CODE
  __sidata = LOADADDR(.data);

  .bss (NOLOAD) : ALIGN(4)
  {{
    __sbss = .;
    *(.bss .bss.*);
    *(COMMON);
    . = ALIGN(4);
    __ebss = .;
  }} > RAM

  .uninit (NOLOAD) : ALIGN(4)
  {{
    __suninit = .;
    *(.uninit .uninit.*);
    . = ALIGN(4);
    __euninit = .;
  }} > RAM

  __sheap = .;
  _stack_end = .;

  /DISCARD/ :
  {{
    *(.ARM.exidx .ARM.exidx.* .ARM.extab.*);
  }}
}}

ASSERT(_stack_end <= _stack_start, \"the statics do not leave room for a stack\");
"
    )
}

/// Runs the image in QEMU (with a time limit) and returns what it printed.
fn qemu(image: &std::path::Path) -> Result<String, String> {
    let mut cmd = Command::new("qemu-system-arm");
    cmd.args([
        "-machine",
        "mps2-an386",
        "-cpu",
        "cortex-m4",
        "-nographic",
        "-monitor",
        "none",
        "-serial",
        "none",
        "-semihosting-config",
        "enable=on,target=native",
        "-icount",
        "shift=0",
        "-kernel",
    ])
    .arg(image)
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::piped());
    eprintln!(
        "$ qemu-system-arm -machine mps2-an386 … -icount shift=0 -kernel {}",
        image.display()
    );
    let started = Instant::now();
    let mut child = cmd
        .spawn()
        .map_err(|e| format!("could not start qemu-system-arm: {e}"))?;
    let mut stdout = child.stdout.take().ok_or("no QEMU stdout")?;
    let mut stderr = child.stderr.take().ok_or("no QEMU stderr")?;
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stdout.read_to_string(&mut text);
        text
    });
    let err_reader = std::thread::spawn(move || {
        let mut text = String::new();
        let _ = stderr.read_to_string(&mut text);
        text
    });
    let status = loop {
        if let Some(status) = child.try_wait().map_err(|e| e.to_string())? {
            break status;
        }
        if started.elapsed() > QEMU_TIMEOUT {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("QEMU did not finish within {QEMU_TIMEOUT:?}"));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let text = reader.join().unwrap_or_default();
    let errors = err_reader.join().unwrap_or_default();
    eprintln!("pil: QEMU ran {:.1} s", started.elapsed().as_secs_f64());
    if !status.success() {
        let tail: Vec<&str> = text.lines().rev().take(5).collect();
        return Err(format!(
            "QEMU exited with {status}: {}{}",
            errors.trim(),
            tail.into_iter().rev().collect::<Vec<_>>().join("\n")
        ));
    }
    Ok(text)
}

/// Frames one control step sent: id and data.
pub type Frames = Vec<(u16, Vec<u8>)>;

/// What the image printed.
struct PilRun {
    /// Calibration: instructions and SysTick ticks.
    cal: (u64, u64),
    /// SysTick ticks of reading the timer twice.
    base: u64,
    /// Per control step: tick, SysTick ticks, frames sent.
    ticks: Vec<(u32, u64, Frames)>,
    /// Peak stack, bytes.
    stack: u64,
}

impl PilRun {
    fn parse(text: &str) -> Result<Self, String> {
        let mut run = PilRun {
            cal: (0, 0),
            base: 0,
            ticks: Vec::new(),
            stack: 0,
        };
        let mut ended = false;
        for line in text.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            let num = |i: usize| -> Result<u64, String> {
                words
                    .get(i)
                    .and_then(|w| w.parse().ok())
                    .ok_or_else(|| format!("bad PIL output line `{line}`"))
            };
            match words.first().copied() {
                Some("PIL-CAL") => run.cal = (num(1)?, num(2)?),
                Some("PIL-BASE") => run.base = num(1)?,
                Some("T") => {
                    let tick = u32::try_from(num(1)?).map_err(|e| e.to_string())?;
                    run.ticks.push((tick, num(2)?, Vec::new()));
                }
                Some("F") => {
                    let id = words
                        .get(1)
                        .and_then(|w| u16::from_str_radix(w, 16).ok())
                        .ok_or_else(|| format!("bad PIL output line `{line}`"))?;
                    let data = unhex(words.get(2).copied().unwrap_or(""))
                        .ok_or_else(|| format!("bad PIL output line `{line}`"))?;
                    run.ticks
                        .last_mut()
                        .ok_or("a frame before the first tick")?
                        .2
                        .push((id, data));
                }
                Some("PIL-STACK") => run.stack = num(1)?,
                Some("PIL-END") => ended = true,
                Some("PIL-FAIL") => return Err(format!("the PIL image failed: {line}")),
                _ => {}
            }
        }
        if !ended {
            return Err("the PIL image stopped before its end mark".into());
        }
        if run.cal.1 == 0 {
            return Err("no calibration from the PIL image".into());
        }
        Ok(run)
    }

    /// Instructions per SysTick tick, from the calibration loop.
    fn instructions_per_tick(&self) -> f64 {
        self.cal.0 as f64 / self.cal.1 as f64
    }
}

fn unhex(text: &str) -> Option<Vec<u8>> {
    if text.len() % 2 != 0 {
        return None;
    }
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect()
}

/// The host build of the core on the same inputs.
fn host_replay(recording: &Recording) -> Result<Vec<Frames>, String> {
    let rate = TickRate::new(u32::from(recording.control_hz))
        .ok_or_else(|| format!("bad control rate {}", recording.control_hz))?;
    let mut node =
        Node::new(Config::ROBOT.at_rate(rate)).map_err(|e| format!("config rejected: {e:?}"))?;
    let mut out = Vec::with_capacity(recording.ticks.len());
    for (k, frames) in recording.ticks.iter().enumerate() {
        let now = Tick(recording.first_tick.wrapping_add(k as u32));
        for (id, data) in frames {
            let _ = node.on_frame(now, *id, data);
        }
        let (_, sent) = node.poll(now);
        out.push(sent.iter().map(|f| (f.id(), f.data().to_vec())).collect());
    }
    Ok(out)
}

/// The outcome of comparing the two builds.
#[derive(Default)]
struct Check {
    frames: u64,
    values: u64,
    /// Values that differ by one count.
    off_by_one: u64,
    /// Largest difference in physical units, and where.
    max_deviation: f64,
    max_at: String,
}

fn compare(host: &[Frames], pil: &[(u32, u64, Frames)]) -> Result<Check, String> {
    if host.len() != pil.len() {
        return Err(format!(
            "PIL ran {} ticks, the host {}",
            pil.len(),
            host.len()
        ));
    }
    let mut check = Check::default();
    for (k, (host_frames, (tick, _, pil_frames))) in host.iter().zip(pil).enumerate() {
        let ids = |f: &Frames| f.iter().map(|(id, _)| *id).collect::<Vec<_>>();
        if ids(host_frames) != ids(pil_frames) {
            return Err(format!(
                "tick {tick} (step {k}): PIL sent ids {:03x?}, the host {:03x?}",
                ids(pil_frames),
                ids(host_frames)
            ));
        }
        for ((id, host_data), (_, pil_data)) in host_frames.iter().zip(pil_frames) {
            check.frames += 1;
            compare_frame(*tick, *id, host_data, pil_data, &mut check)?;
        }
    }
    Ok(check)
}

fn compare_frame(
    tick: u32,
    id: u16,
    host: &[u8],
    pil: &[u8],
    check: &mut Check,
) -> Result<(), String> {
    let message =
        MessageId::from_raw(id).ok_or_else(|| format!("tick {tick}: unknown id {id:#x}"))?;
    let layout = message.layout();
    for (who, data) in [("host", host), ("PIL", pil)] {
        protocol::decode_frame(id, data).map_err(|e| {
            format!(
                "tick {tick}: {} from the {who} does not decode: {e:?}",
                layout.name
            )
        })?;
    }
    if host.len() != pil.len() {
        return Err(format!("tick {tick}: {}: lengths differ", layout.name));
    }
    let payload: usize = layout.fields.iter().map(Field::bytes).sum();
    let mut at = layout.len - payload;
    for field in layout.fields {
        for i in 0..field.count() {
            let name = match field.instances.get(i) {
                Some(instance) => format!("{}.{}_{instance}", layout.name, field.name),
                None => format!("{}.{}", layout.name, field.name),
            };
            let (a, b) = (raw(field.ty, host, at), raw(field.ty, pil, at));
            at += field.ty.bytes();
            check.values += 1;
            let counts = (a - b).abs();
            if counts == 0 {
                continue;
            }
            // Scaled quantities may differ by one count (float rounding before quantising);
            // enumerations, flags, counters and ticks must be equal.
            let scaled = field.exp10 < 0 && field.values.is_empty() && field.flags.is_empty();
            let scale = 10_f64.powi(i32::from(field.exp10));
            if !scaled || counts > 1 {
                return Err(format!(
                    "tick {tick}: {name} differs: host {} vs PIL {} {} (raw {a} vs {b})",
                    a as f64 * scale,
                    b as f64 * scale,
                    field.unit
                ));
            }
            check.off_by_one += 1;
            let deviation = counts as f64 * scale;
            if deviation > check.max_deviation {
                check.max_deviation = deviation;
                check.max_at = format!("{name} at tick {tick} ({deviation} {})", field.unit);
            }
        }
    }
    Ok(())
}

fn raw(ty: WireType, data: &[u8], at: usize) -> i64 {
    let byte = |i: usize| data.get(at + i).copied().unwrap_or(0);
    match ty {
        WireType::U8 => i64::from(byte(0)),
        WireType::I16 => i64::from(i16::from_le_bytes([byte(0), byte(1)])),
        WireType::U16 => i64::from(u16::from_le_bytes([byte(0), byte(1)])),
        WireType::U32 => i64::from(u32::from_le_bytes([byte(0), byte(1), byte(2), byte(3)])),
    }
}

fn report(recording: &Recording, pil: &PilRun, check: &Check) -> Result<(), String> {
    let per_tick = pil.instructions_per_tick();
    let mut instructions: Vec<u64> = pil
        .ticks
        .iter()
        .map(|(_, cost, _)| (cost.saturating_sub(pil.base) as f64 * per_tick).round() as u64)
        .collect();
    instructions.sort_unstable();
    let median = instructions
        .get(instructions.len() / 2)
        .copied()
        .unwrap_or(0);
    let max = instructions.last().copied().unwrap_or(0);
    let seconds = recording.ticks.len() as f64 / f64::from(recording.control_hz);
    println!(
        "MEASURED PIL outputs: {} control steps ({seconds:.1} s at {} Hz), {} frames and {} \
         values equal to the host build's; {} values one count apart, max deviation {}",
        pil.ticks.len(),
        recording.control_hz,
        check.frames,
        check.values,
        check.off_by_one,
        if check.off_by_one == 0 {
            "0 (bit-identical)".to_string()
        } else {
            check.max_at.clone()
        }
    );
    println!(
        "MEASURED PIL SysTick calibration: {} instructions in {} ticks = {per_tick:.2} \
         instructions per tick (timer read overhead {} ticks)",
        pil.cal.0, pil.cal.1, pil.base
    );
    println!(
        "MEASURED PIL instructions per control step (frames decoded + step + frames encoded, \
         Cortex-M4F, mcu profile): median {median}, max {max} (budget {INSTRUCTION_BUDGET})"
    );
    println!(
        "MEASURED PIL peak stack: {} bytes (budget {STACK_BUDGET})",
        pil.stack
    );
    if max > INSTRUCTION_BUDGET || pil.stack > STACK_BUDGET {
        return Err("the control step is over its instruction or stack budget".into());
    }
    Ok(())
}

/// `--record`: reruns the closed loop and rewrites the committed recording.
fn record() -> Result<(), String> {
    crate::setup::run()?;
    let raw_path = work_dir()?.join("recorded.raw");
    sh(cargo()
        .args([
            "run",
            "--release",
            "-p",
            "sim-host",
            "--example",
            "pil_record",
            "--",
        ])
        .arg(&raw_path)
        .arg(RECORD_SECONDS))?;
    let raw =
        std::fs::read(&raw_path).map_err(|e| format!("cannot read {}: {e}", raw_path.display()))?;
    let recording = Recording::from_raw(&raw)?;
    let compact = recording.to_compact();
    let out = root().join(RECORDING);
    std::fs::write(&out, &compact).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    eprintln!(
        "pil: recorded {} ticks ({} bytes raw) → {} ({} bytes)",
        recording.ticks.len(),
        raw.len(),
        RECORDING,
        compact.len()
    );
    Ok(())
}

/// The committed recording's frames, tick by tick (the fuzz seeds come from them).
pub fn recorded_ticks() -> Result<Vec<Frames>, String> {
    let path = root().join(RECORDING);
    let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let recording =
        Recording::from_compact(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(recording.ticks)
}

/// The frames the firmware received, tick by tick.
///
/// Raw format (what `pil_record` writes and the image reads): `PIL1`, control rate u16, first
/// tick u32, tick count u32, then per tick a frame count u8 and per frame id u16, length u8 and
/// the data; little-endian. The committed compact format (`PILZ`) has the same header and
/// layout, but each frame's data is XORed with the previous frame of its id (most bytes of
/// slowly changing feedback become zero) and then run-length coded: a byte `n < 0x80` is
/// followed by `n + 1` literal bytes, a byte `n ≥ 0x80` stands for `n − 0x7F` zero bytes.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Recording {
    control_hz: u16,
    first_tick: u32,
    ticks: Vec<Frames>,
}

impl Recording {
    fn from_raw(bytes: &[u8]) -> Result<Self, String> {
        Self::parse(bytes, b"PIL1", |r, len| r.take(len).map(<[u8]>::to_vec))
    }

    fn from_compact(bytes: &[u8]) -> Result<Self, String> {
        let mut previous: std::collections::HashMap<u16, Vec<u8>> = Default::default();
        Self::parse_with(bytes, b"PILZ", |r, id, len| {
            let mut delta = Vec::with_capacity(len);
            while delta.len() < len {
                let token = r.take(1)?[0];
                if token < 0x80 {
                    delta.extend_from_slice(r.take(usize::from(token) + 1)?);
                } else {
                    delta.resize(delta.len() + usize::from(token - 0x7F), 0);
                }
            }
            if delta.len() != len {
                return None;
            }
            let last = previous.entry(id).or_default();
            last.resize(len.max(last.len()), 0);
            let data: Vec<u8> = delta.iter().zip(last.iter()).map(|(d, p)| d ^ p).collect();
            *last = data.clone();
            Some(data)
        })
    }

    fn parse(
        bytes: &[u8],
        magic: &[u8; 4],
        mut data: impl FnMut(&mut Reader, usize) -> Option<Vec<u8>>,
    ) -> Result<Self, String> {
        Self::parse_with(bytes, magic, |r, _, len| data(r, len))
    }

    fn parse_with(
        bytes: &[u8],
        magic: &[u8; 4],
        mut data: impl FnMut(&mut Reader, u16, usize) -> Option<Vec<u8>>,
    ) -> Result<Self, String> {
        let mut r = Reader { bytes, pos: 0 };
        let bad = || "not a recording, or a damaged one".to_string();
        if r.take(4) != Some(magic.as_slice()) {
            return Err(bad());
        }
        let control_hz = r.u16().ok_or_else(bad)?;
        let first_tick = r.u32().ok_or_else(bad)?;
        let count = r.u32().ok_or_else(bad)?;
        let mut ticks = Vec::with_capacity(count as usize);
        for _ in 0..count {
            let n = r.take(1).ok_or_else(bad)?[0];
            let mut frames = Vec::with_capacity(usize::from(n));
            for _ in 0..n {
                let id = r.u16().ok_or_else(bad)?;
                let len = usize::from(r.take(1).ok_or_else(bad)?[0]);
                frames.push((id, data(&mut r, id, len).ok_or_else(bad)?));
            }
            ticks.push(frames);
        }
        if r.pos != bytes.len() {
            return Err(bad());
        }
        Ok(Self {
            control_hz,
            first_tick,
            ticks,
        })
    }

    fn header(&self, magic: &[u8; 4]) -> Vec<u8> {
        let mut out = magic.to_vec();
        out.extend_from_slice(&self.control_hz.to_le_bytes());
        out.extend_from_slice(&self.first_tick.to_le_bytes());
        out.extend_from_slice(&(self.ticks.len() as u32).to_le_bytes());
        out
    }

    fn to_raw(&self) -> Vec<u8> {
        let mut out = self.header(b"PIL1");
        for frames in &self.ticks {
            out.push(frames.len() as u8);
            for (id, data) in frames {
                out.extend_from_slice(&id.to_le_bytes());
                out.push(data.len() as u8);
                out.extend_from_slice(data);
            }
        }
        out
    }

    fn to_compact(&self) -> Vec<u8> {
        let mut out = self.header(b"PILZ");
        let mut previous: std::collections::HashMap<u16, Vec<u8>> = Default::default();
        for frames in &self.ticks {
            out.push(frames.len() as u8);
            for (id, data) in frames {
                out.extend_from_slice(&id.to_le_bytes());
                out.push(data.len() as u8);
                let last = previous.entry(*id).or_default();
                last.resize(data.len().max(last.len()), 0);
                let delta: Vec<u8> = data.iter().zip(last.iter()).map(|(d, p)| d ^ p).collect();
                *last = data.clone();
                encode_runs(&delta, &mut out);
            }
        }
        out
    }
}

/// The run-length code of [`Recording`]'s compact format.
fn encode_runs(bytes: &[u8], out: &mut Vec<u8>) {
    let mut i = 0;
    while i < bytes.len() {
        let zeros = bytes[i..].iter().take(128).take_while(|&&b| b == 0).count();
        if zeros >= 2 || (zeros == 1 && i + 1 == bytes.len()) {
            out.push(0x7F + zeros as u8);
            i += zeros;
            continue;
        }
        // Literals up to the next pair of zeros.
        let mut end = i;
        while end < bytes.len()
            && end - i < 128
            && !(bytes[end] == 0 && bytes.get(end + 1) == Some(&0))
        {
            end += 1;
        }
        out.push((end - i - 1) as u8);
        out.extend_from_slice(&bytes[i..end]);
        i = end;
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let out = self.bytes.get(self.pos..self.pos.checked_add(n)?)?;
        self.pos += n;
        Some(out)
    }

    fn u16(&mut self) -> Option<u16> {
        Some(u16::from_le_bytes(self.take(2)?.try_into().ok()?))
    }

    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compact_format_round_trips() {
        let recording = Recording {
            control_hz: 250,
            first_tick: 7,
            ticks: vec![
                vec![(0x180, vec![1, 0, 0, 0, 5, 0, 0, 9]), (0x10, vec![])],
                vec![(0x180, vec![1, 0, 0, 0, 6, 0, 0, 9])],
                vec![(0x180, (0..64).collect()), (0x181, vec![0; 64])],
                vec![(0x180, vec![0; 3]), (0x181, vec![7; 1])],
            ],
        };
        let compact = recording.to_compact();
        assert_eq!(Recording::from_compact(&compact).unwrap(), recording);
        assert_eq!(Recording::from_raw(&recording.to_raw()).unwrap(), recording);
    }

    fn wheel_command(left: i16, right: i16) -> Vec<u8> {
        use protocol::{AnyMessage, Torque, WheelCommand};
        let torque = [left, right].map(|raw| Torque::from_raw(raw).unwrap());
        AnyMessage::WheelCommand(WheelCommand { torque })
            .encode(3)
            .unwrap()
            .data()
            .to_vec()
    }

    #[test]
    fn a_difference_names_the_tick_and_the_field() {
        let id = MessageId::WheelCommand.raw();
        let mut check = Check::default();
        let same = wheel_command(100, 200);
        compare_frame(5, id, &same, &same, &mut check).unwrap();
        assert_eq!((check.values, check.off_by_one), (2, 0));
        compare_frame(6, id, &same, &wheel_command(100, 201), &mut check).unwrap();
        assert_eq!(check.off_by_one, 1);
        assert!(
            check.max_at.contains("WheelCommand.torque_"),
            "{}",
            check.max_at
        );
        let error = compare_frame(7, id, &same, &wheel_command(100, 250), &mut check).unwrap_err();
        assert!(error.starts_with("tick 7: WheelCommand.torque_"), "{error}");
    }

    #[test]
    fn runs_cover_every_length() {
        for len in 0..300 {
            for pattern in [0_u8, 1, 2] {
                let bytes: Vec<u8> = (0..len)
                    .map(|i| {
                        if (i / 3) % 3 == usize::from(pattern) {
                            0
                        } else {
                            i as u8 | 1
                        }
                    })
                    .collect();
                let mut out = Vec::new();
                encode_runs(&bytes, &mut out);
                let mut r = Reader {
                    bytes: &out,
                    pos: 0,
                };
                let mut back = Vec::new();
                while back.len() < len {
                    let t = r.take(1).unwrap()[0];
                    if t < 0x80 {
                        back.extend_from_slice(r.take(usize::from(t) + 1).unwrap());
                    } else {
                        back.resize(back.len() + usize::from(t - 0x7F), 0);
                    }
                }
                assert_eq!(back, bytes);
                assert_eq!(r.pos, out.len());
            }
        }
    }
}
