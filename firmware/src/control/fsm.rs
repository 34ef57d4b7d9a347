//! The mode machine: what the robot is doing, and what every request does in every state.
//!
//! The report's six keys pick a motion; a real robot also has to change how it stands between
//! them. The legs fold before the wheels drive (`Folding`), the legs take the weight before a
//! trot (`Standing`), and the two stop states (`EStop`, `Fault`) hold until someone acts.
//!
//! # Transition table
//!
//! `Request(·)` is an operator request (teleop frame); `TeleopLost`, `LinkDegraded`,
//! `LegBlocked`, `StepRefused` and `RangeLost` are stop requests the controller makes itself.
//! `Legs(m)` and `Wheels(m)` are the steady states, `Standing(m)` / `Folding(m)` the
//! transitions that end in them on `PoseReached`.
//! `—` means the event leaves the state unchanged.
//!
//! | state ↓ / event → | Stop (X), or a stop of the controller's | Stand           | Trot d (L/K/Walk) | Fold             | Wheel w (W/S/A/Drive/H) | `PoseReached` |
//! |-------------------|-----------------------------------------|-----------------|-------------------|------------------|-------------------------|---------------|
//! | `Hold`            | —                                       | Standing(Stand) | Standing(Trot d)  | Folding(Balance) | Folding(w)              | —             |
//! | `Legs(_)`         | Legs(Stand)                             | Legs(Stand)     | Legs(Trot d)      | Folding(Balance) | Folding(w)              | —             |
//! | `Standing(_)`     | Standing(Stand)                         | Standing(Stand) | Standing(Trot d)  | Folding(Balance) | Folding(w)              | Legs(m)       |
//! | `Folding(_)`      | Folding(Balance)                        | Standing(Stand) | Standing(Trot d)  | Folding(Balance) | Folding(w)              | Wheels(m)     |
//! | `Wheels(_)`       | Wheels(Balance)                         | Standing(Stand) | Standing(Trot d)  | —                | Wheels(w)               | —             |
//! | `Climbing(_)`     | Climbing(Balance)                       | —               | —                 | —                | —                       | Folding(m)    |
//! | `EStop`           | —                                       | —               | —                 | —                | —                       | —             |
//! | `Fault`           | —                                       | —               | —                 | —                | —                       | —             |
//!
//! `Walk` requests `LegMotion::Walk` (the trot at the operator's speed and yaw rate) where the
//! table says `Trot d`, and `Drive` requests `WheelMotion::Velocity` and `Auto` (`H`)
//! `WheelMotion::Auto` where it says `w`.
//!
//! Events that reach every state alike:
//!
//! | event         | result                                                                     |
//! |---------------|----------------------------------------------------------------------------|
//! | `EStopLatch`  | `EStop` from any state                                                     |
//! | `EStopClear`  | `EStop` → `Hold`; no effect elsewhere. The controller applies a release once its controlled stop has ended, and then raises `Fault` if a drive's fault or a frozen SYNC remains |
//! | `Fault`       | `Fault` from any state but `EStop` (an E-stop outranks a fault)            |
//! | `Reset`       | `Fault` → `Hold` (sent when the operator asks to stop and no cause remains); no effect elsewhere |
//!
//! `Climbing(m)` is entered by the controller itself: in the autonomous mode (`Wheels(Auto)`) a
//! stall of the wheels against a step (`StepStall`, no effect elsewhere) starts its climb
//! ([`crate::legs::climb`]), and its end is its `PoseReached`: a fold, then `m`. A stop (the
//! operator's, a lost operator, a lossy link, or a climb given up) makes it `Climbing(Balance)`:
//! the climb goes back to the fold if its legs have not lifted the robot yet, or ends over the
//! step, and the robot balances there instead of driving on. Other requests are not taken
//! while it climbs; an E-stop or a fault ends it at once.
//!
//! `Hold` is where the robot starts and where it returns after a clear or a reset: the drives
//! hold their present positions and nothing moves until the operator asks for a motion.

use protocol::{ControllerMode, TeleopMode};

/// Which way a trot or a wheel drive goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// +x.
    Forward,
    /// −x.
    Backward,
}

/// What the legs do while they carry the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegMotion {
    /// Stand still at the commanded body height.
    Stand,
    /// Trot (diagonal pairs) at the preset stride.
    Trot(Direction),
    /// Trot at the operator's speed and yaw rate ([`TeleopMode::Walk`]).
    Walk,
}

impl LegMotion {
    /// Whether the legs trot (at a preset or at the operator's velocity).
    pub const fn trotting(self) -> bool {
        matches!(self, LegMotion::Trot(_) | LegMotion::Walk)
    }
}

/// What the wheels do while they carry the robot (always balancing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WheelMotion {
    /// Balance in place.
    Balance,
    /// Drive straight.
    Drive(Direction),
    /// Turn in place (differential drive).
    Rotate,
    /// Drive at the operator's speed and yaw rate ([`TeleopMode::Drive`]).
    Velocity,
    /// The autonomous hybrid mode ([`TeleopMode::Auto`]): drive backward at the preset speed
    /// and climb the steps the wheels stall against ([`crate::legs::climb`]).
    Auto,
}

impl WheelMotion {
    /// Whether the wheels are asked to move (not only to balance in place).
    pub const fn moving(self) -> bool {
        !matches!(self, WheelMotion::Balance)
    }
}

/// The controller's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum State {
    /// Drives hold their positions; nothing moves until a request.
    Hold,
    /// On the legs.
    Legs(LegMotion),
    /// Unfolding onto the legs; then the motion.
    Standing(LegMotion),
    /// Folding onto the wheels; then the motion.
    Folding(WheelMotion),
    /// Balancing on the wheels.
    Wheels(WheelMotion),
    /// Emergency stop: drives torque-free until [`Event::EStopClear`].
    EStop,
    /// Climbing a step behind ([`crate::legs::climb`]); a fold follows, then the motion.
    Climbing(WheelMotion),
    /// A fault stopped the robot until [`Event::Reset`].
    Fault,
}

/// Something that can change the state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Event {
    /// The operator asked for a mode.
    Request(TeleopMode),
    /// The operator's heartbeat stopped: treated as a stop request.
    TeleopLost,
    /// The link monitor found the bus losing too many frames: treated as a stop request (a
    /// controlled stop on the legs or the wheels, not a fault that drops the robot).
    LinkDegraded,
    /// The trot's leading feet could not finish their swings ([`crate::legs::blocked`]):
    /// treated as a stop request (the robot stands on four legs).
    LegBlocked,
    /// The autonomous mode's wheels stalled against a step: its climb starts.
    StepStall,
    /// The running climb gave up (a step out of its range, or no ground within reach):
    /// treated as a stop request.
    StepRefused,
    /// The autonomous mode heard no ranging for too long (it would drive blind): treated as
    /// a stop request.
    RangeLost,
    /// The legs arrived at the pose of the running transition.
    PoseReached,
    /// An E-stop frame asked to latch.
    EStopLatch,
    /// An E-stop frame asked to clear.
    EStopClear,
    /// The safety supervisor found a fault.
    Fault,
    /// The operator asked to stop and no fault cause remains.
    Reset,
}

impl State {
    /// Power-on state.
    pub const INITIAL: State = State::Hold;

    /// The state after `event`. Total: every event has a result in every state.
    pub fn next(self, event: Event) -> State {
        match (self, event) {
            (_, Event::EStopLatch) => State::EStop,
            (State::EStop, Event::EStopClear) => State::Hold,
            (State::EStop, _) => State::EStop,
            (_, Event::Fault) => State::Fault,
            (State::Fault, Event::Reset) => State::Hold,
            (State::Fault, _) => State::Fault,
            (_, Event::EStopClear | Event::Reset) => self,
            (State::Standing(motion), Event::PoseReached) => State::Legs(motion),
            (State::Folding(motion), Event::PoseReached) => State::Wheels(motion),
            (State::Climbing(motion), Event::PoseReached) => State::Folding(motion),
            (
                State::Climbing(_),
                Event::Request(TeleopMode::Stop)
                | Event::TeleopLost
                | Event::LinkDegraded
                | Event::LegBlocked
                | Event::StepRefused
                | Event::RangeLost,
            ) => State::Climbing(WheelMotion::Balance),
            (State::Climbing(_), _) => self,
            (State::Wheels(WheelMotion::Auto), Event::StepStall) => {
                State::Climbing(WheelMotion::Auto)
            }
            (_, Event::StepStall) => self,
            (_, Event::PoseReached) => self,
            (
                _,
                Event::TeleopLost
                | Event::LinkDegraded
                | Event::LegBlocked
                | Event::StepRefused
                | Event::RangeLost,
            ) => self.on_request(TeleopMode::Stop),
            (_, Event::Request(mode)) => self.on_request(mode),
        }
    }

    fn on_request(self, mode: TeleopMode) -> State {
        let on_wheels = matches!(self, State::Folding(_) | State::Wheels(_));
        match mode {
            TeleopMode::Stop => match self {
                State::Legs(_) => State::Legs(LegMotion::Stand),
                State::Standing(_) => State::Standing(LegMotion::Stand),
                State::Folding(_) => State::Folding(WheelMotion::Balance),
                State::Wheels(_) => State::Wheels(WheelMotion::Balance),
                other => other,
            },
            TeleopMode::Stand => self.to_legs(LegMotion::Stand),
            TeleopMode::TrotForward => self.to_legs(LegMotion::Trot(Direction::Forward)),
            TeleopMode::TrotBackward => self.to_legs(LegMotion::Trot(Direction::Backward)),
            TeleopMode::Fold if on_wheels => match self {
                State::Folding(_) => State::Folding(WheelMotion::Balance),
                other => other,
            },
            TeleopMode::Fold => State::Folding(WheelMotion::Balance),
            TeleopMode::WheelForward => self.to_wheels(WheelMotion::Drive(Direction::Forward)),
            TeleopMode::WheelBackward => self.to_wheels(WheelMotion::Drive(Direction::Backward)),
            TeleopMode::WheelRotate => self.to_wheels(WheelMotion::Rotate),
            TeleopMode::Drive => self.to_wheels(WheelMotion::Velocity),
            TeleopMode::Walk => self.to_legs(LegMotion::Walk),
            TeleopMode::Auto => self.to_wheels(WheelMotion::Auto),
        }
    }

    fn to_legs(self, motion: LegMotion) -> State {
        match self {
            State::Legs(_) => State::Legs(motion),
            _ => State::Standing(motion),
        }
    }

    fn to_wheels(self, motion: WheelMotion) -> State {
        match self {
            State::Wheels(_) => State::Wheels(motion),
            _ => State::Folding(motion),
        }
    }

    /// The mode reported on the bus.
    pub fn mode(self) -> ControllerMode {
        match self {
            State::Hold | State::Legs(LegMotion::Stand) | State::Wheels(WheelMotion::Balance) => {
                ControllerMode::Stop
            }
            State::Legs(LegMotion::Trot(Direction::Forward)) => ControllerMode::TrotForward,
            State::Legs(LegMotion::Trot(Direction::Backward)) => ControllerMode::TrotBackward,
            State::Standing(_) => ControllerMode::Standing,
            State::Climbing(_) => ControllerMode::Climbing,
            State::Wheels(WheelMotion::Auto) => ControllerMode::Auto,
            State::Folding(_) => ControllerMode::Folding,
            State::Wheels(WheelMotion::Drive(Direction::Forward)) => ControllerMode::WheelForward,
            State::Wheels(WheelMotion::Drive(Direction::Backward)) => ControllerMode::WheelBackward,
            State::Wheels(WheelMotion::Rotate) => ControllerMode::WheelRotate,
            State::Legs(LegMotion::Walk) => ControllerMode::Walking,
            State::Wheels(WheelMotion::Velocity) => ControllerMode::Driving,
            State::EStop => ControllerMode::EStop,
            State::Fault => ControllerMode::Fault,
        }
    }

    /// Whether the wheels carry (or are about to carry) the robot, so the balance law may run
    /// (a climb holds them still instead while its feet are down).
    pub fn balancing(self) -> bool {
        matches!(
            self,
            State::Folding(_) | State::Wheels(_) | State::Standing(_) | State::Climbing(_)
        )
    }
}
