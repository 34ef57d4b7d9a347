//! The E-stop contract as an oracle: every frame and every tick of the node under test passes
//! through [`Oracle::deliver`] and [`Oracle::poll`], which keep a model of what the node must
//! do and panic (a crash libFuzzer reports, with its input) where it does otherwise.
//!
//! - **Latch**: a frame that decodes as an E-stop latch always latches (never refused, never
//!   limited); nothing else latches.
//! - **No release without a fresh, authenticated one**: once latched, the node leaves the latch
//!   only on the first delivery of a release sealed under the key in the present epoch whose
//!   token is the one the node publishes at that moment. A replayed frame, a release of
//!   another epoch or key, one with a wrong or earlier token, a corrupted one never releases.
//!   A release heard while the controlled stop still runs takes effect on the stop's first
//!   torque-free tick, unless a later latch cancels it.
//! - **No motion command obeyed while latched**: the state is `EStop` and the status says so
//!   at every tick, and the drive commands (legs enabled, leg targets, wheel torques) are
//!   exactly those of a twin node that heard every frame but the operator's (commands,
//!   heartbeats): the stop depends on nothing the operator sends.
//! - **SS1**: every drive command is torque-free (legs disabled, wheel torque 0, in the output
//!   and in the `LegTargets` and `WheelCommand` frames) from one tick before
//!   [`SS1_DEADLINE_MS`] after the latch (the stop's own cut: the drives time the deadline from
//!   the latch frame, which the controller may hear a tick late), counted in ticks and in polls
//!   alike (a frozen or backward SYNC does not stretch it), and from the first torque-free tick
//!   on until the release; a latch restored after a restart is torque-free at once.
//! - **Restart**: the latch survives it.
//! - **Restart interlock**: after the start, a restart or a release, until the node accepts an
//!   operator STOP, it stays in `Hold` or `Fault`, commands no wheel torque and keeps every
//!   enabled leg target where it was.
//! - **Replays**: a replayed frame other than a latch is refused. (A frame sealed under the key
//!   for a later epoch and replayed in that epoch's session, which never heard it, is fresh to
//!   the node: the bench hands it over as fresh, and the release rule above judges it.)
//! - **A release is no fault reset** (checked with [`CHECK_FAULT_AFTER_RELEASE`]): the robot
//!   is never in motion (standing up, on its legs, folding, on its wheels) while a fault cause
//!   that only `Fault` holds is reported — a drive's fault, a SYNC that froze or went back —
//!   as `Fault` leaves only on a STOP with no cause left.
//!
//! With `ESTOP_TRACE` set in the environment, every frame of the operator, the tool and the
//! simulator, every replay and every change of state is printed (to read a crash's input:
//! `ESTOP_TRACE=1 fuzz/target/…/release/estop fuzz/artifacts/estop/crash-…`).

use firmware::control::controller::Output;
use firmware::control::fsm::State;
use firmware::control::safety::SS1_DEADLINE_MS;
use firmware::{Node, Tick};
use protocol::{
    decode_frame, AnyMessage, ControllerMode, DecodeError, DriveEnable, EStop, EStopAction,
    FaultFlags, Frame, Joints, MessageId, TeleopMode,
};

/// Whether to check that a release leaves no fault behind (the seeds `fault_after_release_*`
/// latch and release while a drive's fault or a frozen SYNC remains). A switch so that the
/// oracle's own break check can show the check fails on a firmware that resets a fault on
/// release (docs/faults.md).
const CHECK_FAULT_AFTER_RELEASE: bool = true;

/// Where a delivered frame came from: what decides whether a release in it is legitimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    /// Sealed under the key in the session of this epoch (delivered at once or held back).
    Fresh {
        /// The epoch it was sealed in.
        epoch: u32,
    },
    /// Sealed without the key, or corrupted after sealing.
    Forged,
    /// A copy of a frame delivered before.
    Replay,
}

/// The latch the node is in.
#[derive(Debug, Clone, Copy)]
struct Latched {
    /// The tick the latch frame was delivered at.
    at: Tick,
    /// Ticks computed since.
    polls: u32,
    /// Whether a tick since was torque-free (then every later one must be).
    off: bool,
    /// Whether a fresh authenticated release was delivered while the stop still ran: the node
    /// must take it on the first torque-free tick, and not before.
    release_heard: bool,
}

/// The contract's model of the node under test.
#[derive(Debug)]
pub struct Oracle {
    /// Ticks from the latch at which every drive must be torque-free.
    cut_ticks: u32,
    /// The epoch of the node's session.
    epoch: u32,
    latched: Option<Latched>,
    /// The twin that hears no operator frame, while latched.
    twin: Option<Node>,
    /// Until an operator STOP: the enabled leg targets held (`Some(None)`: none seen yet).
    awaiting_stop: Option<Option<Joints<f32>>>,
    /// The state at the last tick (for the trace).
    state: Option<State>,
}

/// Whether to print the trace (`ESTOP_TRACE` set).
fn tracing() -> bool {
    static ON: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ON.get_or_init(|| std::env::var_os("ESTOP_TRACE").is_some())
}

impl Oracle {
    /// The model of `node`, just started in `epoch`.
    pub fn new(node: &Node, epoch: u32) -> Oracle {
        let rate = node.controller().config().rate;
        Oracle {
            cut_ticks: rate.ticks_from_ms(SS1_DEADLINE_MS).saturating_sub(1),
            epoch,
            latched: None,
            twin: None,
            awaiting_stop: Some(None),
            state: None,
        }
    }

    /// Hands `frame` to `node` at `now` (and to the twin, unless it is the operator's) and
    /// checks what it did.
    pub fn deliver(
        &mut self,
        node: &mut Node,
        now: Tick,
        frame: &Frame,
        origin: Origin,
    ) -> Result<(), DecodeError> {
        let (id, data) = (frame.id(), frame.data());
        let message = decode_frame(id, data).ok().map(|d| d.message);
        let latch = matches!(
            message,
            Some(AnyMessage::EStop(EStop {
                action: EStopAction::Latch,
                ..
            }))
        );
        let legit_release = origin == (Origin::Fresh { epoch: self.epoch })
            && matches!(message, Some(AnyMessage::EStop(EStop {
                action: EStopAction::Clear,
                token,
                ..
            })) if token == node.release_token());
        let result = node.on_frame(now, id, data);
        if tracing() && (id < 0x100 || id >= 0x200 || origin == Origin::Replay) {
            eprintln!("{:>10} {origin:?} {id:03X} {message:?}: {result:?}", now.0);
        }
        if let Some(twin) = self.twin.as_mut().filter(|_| !from_operator(id)) {
            let _ = twin.on_frame(now, id, data);
        }
        if origin == Origin::Replay && !latch {
            assert!(
                result.is_err(),
                "replayed frame {id:03X} {data:02X?} was accepted"
            );
        }
        if latch && origin != Origin::Forged {
            assert!(
                result.is_ok() && node.estop_latched(),
                "latch {id:03X} {data:02X?} did not latch: {result:?}"
            );
        }
        match (self.latched.is_some(), node.estop_latched()) {
            (true, false) => {
                let stopped = self.latched.is_some_and(|latched| latched.off);
                assert!(
                    stopped,
                    "released by frame {id:03X} while the controlled stop still ran"
                );
                assert!(
                    legit_release,
                    "released by {origin:?} frame {id:03X} {data:02X?} ({message:?}), which is \
                     not a fresh authenticated release of token {:?} in epoch {}",
                    node.release_token(),
                    self.epoch
                );
                self.latched = None;
                self.twin = None;
                self.awaiting_stop = Some(None);
            }
            (false, true) => {
                assert!(
                    latch,
                    "latched by {id:03X} {data:02X?} ({message:?}), not a latch"
                );
                self.latched = Some(Latched {
                    at: now,
                    polls: 0,
                    off: false,
                    release_heard: false,
                });
                self.twin = Some(node.clone());
            }
            (true, true) => {
                if let Some(latched) = self.latched.as_mut().filter(|_| result.is_ok()) {
                    if legit_release {
                        latched.release_heard = true;
                    } else if latch {
                        // A later latch cancels a release that waits.
                        latched.release_heard = false;
                    }
                }
            }
            _ => {}
        }
        let stop =
            matches!(message, Some(AnyMessage::TeleopCommand(c)) if c.mode == TeleopMode::Stop);
        if stop && result.is_ok() {
            self.awaiting_stop = None;
        }
        result
    }

    /// Runs tick `now` on `node` (and the twin) and checks its output; returns it.
    pub fn poll(&mut self, node: &mut Node, now: Tick) -> Output {
        let (output, frames) = node.poll(now);
        let state = node.controller().state();
        if tracing() && self.state.replace(state) != Some(state) {
            eprintln!("{:>10} tick: {state:?}, {:?}", now.0, drives(&output));
        }
        if let Some(twin) = self.twin.as_mut() {
            let (alone, _) = twin.poll(now);
            assert!(
                drives(&output) == drives(&alone) && output.status.mode == alone.status.mode,
                "tick {}: the operator's frames changed the latched stop: {output:?}, without \
                 them {alone:?}",
                now.0
            );
        }
        let released = self.latched.is_some() && !node.estop_latched();
        if let Some(latched) = self.latched.filter(|_| released) {
            check_deferred_release(now, &latched, &output);
            self.latched = None;
            self.twin = None;
            self.awaiting_stop = Some(None);
        } else if let Some(latched) = self.latched.as_mut() {
            let waited = latched.release_heard && latched.off;
            check_latched(node, now, latched, self.cut_ticks, &output, &frames);
            assert!(
                !waited,
                "tick {}: a release heard during the stop still waits after its end",
                now.0
            );
        } else if let Some(held) = self.awaiting_stop.as_mut() {
            check_interlocked(node, now, held, &output);
        }
        if CHECK_FAULT_AFTER_RELEASE {
            check_no_motion_in_fault(state, &output);
        }
        output
    }

    /// Takes `node`, the controller restarted in `epoch` with what it persisted.
    pub fn restart(&mut self, node: &Node, epoch: u32) {
        self.epoch = epoch;
        self.awaiting_stop = Some(None);
        assert_eq!(
            node.estop_latched(),
            self.latched.is_some(),
            "the latch did not survive the restart"
        );
        if let Some(latched) = self.latched.as_mut() {
            // Restored unarmed: nothing to bring to rest, torque-free at once; a release that
            // waited is forgotten with the rest of the controller's state.
            latched.off = true;
            latched.release_heard = false;
            self.twin = Some(node.clone());
        }
    }
}

/// Whether `id` is the operator's (what must not change a latched stop).
fn from_operator(id: u16) -> bool {
    id == MessageId::TeleopCommand.raw() || id == MessageId::TeleopHeartbeat.raw()
}

/// What the drives are told: legs enabled, leg targets, wheel torques.
fn drives(output: &Output) -> (bool, Joints<f32>, [f32; 2]) {
    (
        output.legs_enabled,
        output.leg_targets_rad,
        output.wheel_torque_nm,
    )
}

fn torque_free(output: &Output) -> bool {
    !output.legs_enabled && output.wheel_torque_nm == [0.0, 0.0]
}

/// Latched: `EStop` reported, and torque-free from the cut on (output and frames).
fn check_latched(
    node: &Node,
    now: Tick,
    latched: &mut Latched,
    cut_ticks: u32,
    output: &Output,
    frames: &[Frame],
) {
    let t = now.0;
    assert_eq!(
        node.controller().state(),
        State::EStop,
        "tick {t}: left the latch"
    );
    assert_eq!(output.status.mode, ControllerMode::EStop, "tick {t}");
    assert!(
        output.status.faults.contains(FaultFlags::ESTOP_LATCHED),
        "tick {t}"
    );
    let elapsed = latched.polls.max(now.since(latched.at));
    latched.polls = latched.polls.saturating_add(1);
    let free = torque_free(output);
    if latched.off || elapsed >= cut_ticks {
        assert!(
            free,
            "tick {t}, {elapsed} ticks after the latch (cut at {cut_ticks}, torque-free before: \
             {}): a drive is powered: {output:?}",
            latched.off
        );
        for frame in frames {
            match decode_frame(frame.id(), frame.data()).map(|d| d.message) {
                Ok(AnyMessage::LegTargets(legs)) => {
                    assert_eq!(legs.enable, DriveEnable::Disabled, "tick {t}: legs enabled");
                }
                Ok(AnyMessage::WheelCommand(wheels)) => {
                    let torques = wheels.torque.map(|torque| torque.raw());
                    assert_eq!(torques, [0, 0], "tick {t}: wheel torque on the bus");
                }
                _ => {}
            }
        }
    }
    latched.off |= free;
}

/// Left the latch on a tick, not on a frame: only a release heard while the stop ran, and only
/// once the stop is torque-free.
fn check_deferred_release(now: Tick, latched: &Latched, output: &Output) {
    let t = now.0;
    assert!(
        latched.release_heard,
        "tick {t}: left the latch without a fresh authenticated release"
    );
    assert!(
        torque_free(output),
        "tick {t}: released before the stop was torque-free: {output:?}"
    );
}

/// Awaiting STOP after a start, restart or release: nothing moves.
fn check_interlocked(node: &Node, now: Tick, held: &mut Option<Joints<f32>>, output: &Output) {
    let t = now.0;
    let state = node.controller().state();
    assert!(
        matches!(state, State::Hold | State::Fault),
        "tick {t}: {state:?} before a STOP after the start, a restart or a release"
    );
    assert_eq!(
        output.wheel_torque_nm,
        [0.0, 0.0],
        "tick {t}: wheels driven in {state:?}"
    );
    if output.legs_enabled {
        let targets = *held.get_or_insert(output.leg_targets_rad);
        assert!(
            targets == output.leg_targets_rad,
            "tick {t}: the legs moved before a STOP: {targets:?} to {:?}",
            output.leg_targets_rad
        );
    }
}

/// No motion while a cause that only `Fault` holds (a drive fault, a stalled SYNC) is reported.
fn check_no_motion_in_fault(state: State, output: &Output) {
    let moving = matches!(
        state,
        State::Standing(_) | State::Legs(_) | State::Folding(_) | State::Wheels(_)
    );
    let faults = output.status.faults;
    let held = faults.contains(FaultFlags::DRIVE_FAULT) || faults.contains(FaultFlags::SYNC_LOST);
    assert!(
        !(moving && held),
        "tick {}: {state:?} with faults {faults:?}",
        output.status.tick.0
    );
}
