//! The input language of the `estop` target: a header, then operations, each a code byte and
//! its argument bytes. Every byte string is a script (an unknown code is taken modulo the
//! number of operations, missing arguments read as 0), so the fuzzer mutates scripts rather
//! than bytes. Shared with `cargo xtask fuzz --seeds`, which writes the seeds below with it, so
//! that the committed seeds and the target read the same language.
//!
//! Header ([`HEADER_LEN`] bytes): `setup` (control rate [`RATES_HZ`]`[setup % 3]`; bit 7:
//! start `4 × start` ticks before `u32::MAX`, so that the tick wraps in the run, else at
//! `4 × start`), `start`, `epoch` (the first session's epoch is `1 + 257 × epoch`, so the
//! release token, seeded from the epoch's low 16 bits, wraps too).
#![allow(dead_code)]

/// Bytes before the first operation.
pub const HEADER_LEN: usize = 3;

/// The control rates a script may pick: the simulator's, a slow one (whose SS1 deadline is 200
/// ticks away), the MCU's.
pub const RATES_HZ: [u32; 3] = [250, 100, 1000];

/// Indices into [`RATES_HZ`], for scripts.
pub const HZ_250: u8 = 0;
pub const HZ_100: u8 = 1;
pub const HZ_1000: u8 = 2;

/// Most payload bytes a [`Op::Message`] carries (a CAN FD frame's 64 less the E2E header).
pub const MAX_PAYLOAD: usize = 58;

/// One operation on the controller and its bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Op {
    /// `[n]`: `1 + n % 32` control ticks pass on the node's own clock (wall-clock runner).
    Tick,
    /// `[n]`: `32 × (1 + n % 32)` control ticks pass (up to 1024: past any SS1 deadline).
    Run,
    /// `[kind, n]`: a SYNC names the next tick (lockstep): `kind % 4` = 0 advancing by
    /// `1 + n % 4`, 1 frozen (the last tick again), 2 backward by `1 + n`, 3 a jump of
    /// `n × 4096` ticks; the node computes that tick.
    Sync,
    /// `[mode, wheel, pitch]`: the plant's feedback from now on, sent every 20 ms:
    /// `mode % 4` = 0 none, 1 joints where the enabled drives were commanded, 2 the stance,
    /// 3 the fold; wheel rate `wheel as i8 × 0.05` rad/s, pitch `pitch as i8 × 0.5°`. With bit
    /// 2 of `mode` the operator sends its heartbeat every 20 ms, with bit 3 its last command.
    Plant,
    /// `[mode, height, speed]`: a fresh operator command, mode `mode % 8` (wire order: X W S A
    /// L K stand fold), body height `height as i8` mm, speed scale `speed % 101` %.
    Command,
    /// `[]`: a fresh operator heartbeat.
    Heartbeat,
    /// `[id, len, payload…]`: any message the controller hears (`id` modulo that list), from
    /// `len % 59` payload bytes, sealed fresh by its sender if it decodes.
    Message,
    /// `[form]`: an E-stop latch, `form % 4` = the classic 8-byte frame from a tool or from the
    /// teleop, a full frame sealed by the teleop, a full frame bound to no session.
    Latch,
    /// `[source]`: a fresh authenticated release echoing the token the node publishes, from
    /// the teleop (`source` even) or a tool.
    Release,
    /// `[kind, n]`: a forged release, `kind % 5` = a wrong token, a token published earlier, a
    /// release sealed in another epoch, one under another key, a fresh one with a bit flipped.
    Forge,
    /// `[source]`: seals a fresh release with the published token and holds it back.
    Withhold,
    /// `[]`: delivers the release held back (its first delivery), if any.
    Deliver,
    /// `[n]`: replays the frame delivered `n` frames before the last (of those kept).
    Replay,
    /// `[n, k]`: replays `1 + k % 16` consecutive frames, from the one `n` before the last.
    ReplayRun,
    /// `[kind]`: the controller restarts with the next epoch, its latch restored as
    /// firmware-host restores it; `kind` odd: its clock restarts at tick 0.
    Restart,
}

impl Op {
    /// Every operation, by code.
    pub const ALL: [Op; 15] = [
        Op::Tick,
        Op::Run,
        Op::Sync,
        Op::Plant,
        Op::Command,
        Op::Heartbeat,
        Op::Message,
        Op::Latch,
        Op::Release,
        Op::Forge,
        Op::Withhold,
        Op::Deliver,
        Op::Replay,
        Op::ReplayRun,
        Op::Restart,
    ];

    /// The operation a code byte stands for.
    pub fn of(code: u8) -> Op {
        Op::ALL[usize::from(code) % Op::ALL.len()]
    }

    /// The code byte of this operation.
    pub fn code(self) -> u8 {
        Op::ALL.iter().position(|op| *op == self).unwrap_or(0) as u8
    }

    /// Argument bytes after the code (for [`Op::Message`], before its payload).
    pub const fn args(self) -> usize {
        match self {
            Op::Heartbeat | Op::Deliver => 0,
            Op::Tick | Op::Run | Op::Latch | Op::Release | Op::Withhold | Op::Replay => 1,
            Op::Restart => 1,
            Op::Sync | Op::Forge | Op::ReplayRun | Op::Message => 2,
            Op::Plant | Op::Command => 3,
        }
    }
}

/// Operator modes by their wire value, for scripts.
pub mod mode {
    pub const STOP: u8 = 0;
    pub const WHEEL_FORWARD: u8 = 1;
    pub const WHEEL_ROTATE: u8 = 3;
    pub const TROT_FORWARD: u8 = 4;
    pub const STAND: u8 = 6;
    pub const FOLD: u8 = 7;
}

/// Writes a script.
#[derive(Debug, Clone)]
pub struct Script(Vec<u8>);

impl Script {
    /// A script at rate `RATES_HZ[rate]`, starting `wrap_in × 4` ticks before the tick wraps
    /// (or at tick 0), in the session of epoch `1 + 257 × epoch`.
    pub fn new(rate: u8, wrap_in: Option<u8>, epoch: u8) -> Script {
        let setup = rate | if wrap_in.is_some() { 0x80 } else { 0 };
        Script(vec![setup, wrap_in.unwrap_or(0), epoch])
    }

    /// Appends `op` with `args` (exactly [`Op::args`] of them; a [`Op::Message`] also its
    /// payload).
    pub fn op(mut self, op: Op, args: &[u8]) -> Script {
        let payload = match (op, args.get(1)) {
            (Op::Message, Some(len)) => usize::from(*len) % (MAX_PAYLOAD + 1),
            _ => 0,
        };
        assert_eq!(
            args.len(),
            op.args() + payload,
            "{op:?} takes {} arguments",
            op.args()
        );
        self.0.push(op.code());
        self.0.extend_from_slice(args);
        self
    }

    /// Appends a run of `ticks` ticks (rounded up to the [`Op::Tick`] and [`Op::Run`] steps).
    pub fn ticks(mut self, mut ticks: u32) -> Script {
        while ticks >= 32 {
            let runs = (ticks / 32).min(32);
            self = self.op(Op::Run, &[(runs - 1) as u8]);
            ticks -= runs * 32;
        }
        if ticks > 0 {
            self = self.op(Op::Tick, &[(ticks - 1) as u8]);
        }
        self
    }

    /// Appends an operator command.
    pub fn command(self, mode: u8) -> Script {
        self.op(Op::Command, &[mode, 0, 100])
    }

    /// The bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        self.0
    }
}

/// The ideal plant (joints follow the enabled drives), wheels at rest, torso level, and an
/// operator sending its heartbeat and its last command every 20 ms.
fn plant(script: Script) -> Script {
    script.op(Op::Plant, &[1 | 4 | 8, 0, 0])
}

/// Writes one seed.
type Seed = fn() -> Script;

/// The committed seeds: sessions that reach the contract's corners within the tick budget,
/// for the fuzzer to mutate.
pub fn seeds() -> Vec<(&'static str, Vec<u8>)> {
    let scripts: [(&str, Seed); 9] = [
        ("fault_after_release_sync", sync_fault),
        ("fault_after_release_drive", drive_fault),
        ("on_wheels", on_wheels),
        ("trotting_restart", trotting),
        ("replayed", replayed),
        ("lockstep_wrap", lockstep_wrap),
        ("withheld", withheld),
        ("fast_1khz", fast),
        ("release_sealed_ahead", sealed_ahead),
    ];
    scripts
        .into_iter()
        .map(|(name, script)| (name, script().into_bytes()))
        .collect()
}

/// On the wheels at 250 Hz: latched while driving, the operator holding W; forged releases;
/// torque-free at the deadline; released; W repeated, then X and a new key.
fn on_wheels() -> Script {
    use mode::*;
    plant(Script::new(HZ_250, None, 0))
        .command(STOP)
        .command(WHEEL_FORWARD)
        .ticks(300)
        .op(Op::Latch, &[0])
        .command(WHEEL_FORWARD)
        .ticks(100)
        .op(Op::Forge, &[0, 0])
        .op(Op::Forge, &[1, 0])
        .op(Op::Forge, &[2, 0])
        .op(Op::Forge, &[3, 0])
        .op(Op::Forge, &[4, 77])
        .ticks(420)
        .op(Op::Release, &[1])
        .ticks(20)
        .command(STOP)
        .command(FOLD)
        .ticks(40)
}

/// Trotting at 100 Hz, latched by the teleop, the controller restarted with the latch.
fn trotting() -> Script {
    use mode::*;
    plant(Script::new(HZ_100, None, 3))
        .command(STOP)
        .command(TROT_FORWARD)
        .ticks(150)
        .op(Op::Latch, &[2])
        .ticks(60)
        .op(Op::Restart, &[0])
        .ticks(30)
        .op(Op::Release, &[0])
        .command(TROT_FORWARD)
        .ticks(10)
        .command(STOP)
        .command(STAND)
        .ticks(30)
}

/// Standing at 100 Hz: latched, released, turning, latched again, replays of every kind.
fn replayed() -> Script {
    use mode::*;
    plant(Script::new(HZ_100, None, 1))
        .command(STOP)
        .command(STAND)
        .ticks(100)
        .op(Op::Latch, &[3])
        .op(Op::Release, &[0])
        .command(STOP)
        .command(WHEEL_ROTATE)
        .ticks(100)
        .op(Op::Latch, &[1])
        .op(Op::ReplayRun, &[40, 15])
        .op(Op::Replay, &[3])
        .op(Op::ReplayRun, &[200, 9])
        .ticks(250)
        .op(Op::Replay, &[0])
}

/// Lockstep across the tick's wrap: SYNC advancing, frozen, going back, jumping.
fn lockstep_wrap() -> Script {
    use mode::*;
    plant(Script::new(HZ_250, Some(60), 255))
        .command(STOP)
        .command(FOLD)
        .op(Op::Sync, &[0, 0])
        .op(Op::Sync, &[0, 3])
        .ticks(150)
        .op(Op::Latch, &[0])
        .op(Op::Sync, &[0, 0])
        .op(Op::Sync, &[1, 0])
        .op(Op::Sync, &[2, 5])
        .op(Op::Sync, &[3, 9])
        .ticks(40)
        .op(Op::Release, &[1])
        .command(STOP)
}

/// Releases held back: one across another source's latch, one across a restart; a STOP as any
/// message (message 8: the operator's command).
fn withheld() -> Script {
    use mode::*;
    plant(Script::new(HZ_100, None, 2))
        .command(STOP)
        .command(STAND)
        .ticks(60)
        .op(Op::Latch, &[0])
        .op(Op::Withhold, &[1])
        .op(Op::Latch, &[1])
        .op(Op::Deliver, &[])
        .ticks(220)
        .op(Op::Withhold, &[0])
        .op(Op::Restart, &[1])
        .op(Op::Deliver, &[])
        .op(Op::Heartbeat, &[])
        .op(Op::Release, &[0])
        .op(Op::Message, &[8, 4, STOP, 0, 0, 100])
        .ticks(20)
}

/// The MCU's rate: latched while folding onto the wheels.
fn fast() -> Script {
    use mode::*;
    plant(Script::new(HZ_1000, None, 0))
        .command(STOP)
        .command(WHEEL_FORWARD)
        .ticks(600)
        .op(Op::Latch, &[2])
        .ticks(300)
        .op(Op::Release, &[0])
}

/// A latch and a release while a fault holds: STOP and a new key must start no motion while
/// the cause remains (the oracle's `CHECK_FAULT_AFTER_RELEASE`). Here the SYNC froze before
/// the latch and stays frozen.
fn sync_fault() -> Script {
    use mode::*;
    plant(Script::new(HZ_250, None, 0))
        .command(STOP)
        .ticks(20)
        .op(Op::Sync, &[1, 0])
        .op(Op::Latch, &[0])
        .op(Op::Release, &[1])
        .command(STOP)
        .command(WHEEL_FORWARD)
        .op(Op::Sync, &[1, 0])
        .op(Op::Sync, &[1, 0])
}

/// As `sync_fault`, with a fault raised while latched: the front-left leg drive reports FAULT
/// (message 10: its DriveStatus) once, and nothing since.
fn drive_fault() -> Script {
    use mode::*;
    plant(Script::new(HZ_250, None, 0))
        .command(STOP)
        .ticks(20)
        .op(Op::Latch, &[0])
        .ticks(4)
        .op(Op::Message, &[10, 5, 1 << 2, 0, 0, 0, 0])
        .ticks(4)
        .op(Op::Release, &[1])
        .command(STOP)
        .command(STAND)
        .ticks(16)
}

/// A release sealed under the key for the epoch two restarts ahead, with the token that
/// session's restored latch will publish: refused when sent, it releases when replayed in that
/// session, which never heard it (for the node, a fresh release: the oracle must not call it a
/// replay; the fuzzer found this corner).
fn sealed_ahead() -> Script {
    plant(Script::new(HZ_250, None, 0))
        .command(mode::STOP)
        .ticks(8)
        .op(Op::Latch, &[0])
        .op(Op::Release, &[1])
        .op(Op::Latch, &[0])
        .op(Op::Release, &[1])
        .op(Op::Latch, &[0])
        .op(Op::Forge, &[2, 1])
        .op(Op::Restart, &[1])
        .op(Op::Restart, &[0])
        .op(Op::Replay, &[0])
        .ticks(8)
}
