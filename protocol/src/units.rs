//! Fixed-point quantities, enumerations and flag sets that appear on the wire.
//!
//! Each scalar is an integer count with a decimal scale; its doc comment gives the scale, the
//! unit and the accepted range. A receiver rejects a raw value outside the range as
//! [`RejectCause::OutOfRange`](crate::RejectCause::OutOfRange); a sender builds values with
//! `from_si` (checked) or `saturating_from_si` (clamped).

use crate::wire::{wire_enum, wire_flags, wire_scalar};

wire_scalar!(
    /// Angle: joint position, body tilt. 1e-4 rad, `i16` (±3.2767 rad).
    Angle(i16) = I16, exp10 -4, unit "rad", raw i16::MIN, i16::MAX
);
wire_scalar!(
    /// Wheel angle wrapped to one turn. 1e-4 rad, `i16`, accepted −31416…31416 (±π).
    /// Wheels turn without end; the receiver unwraps from successive samples.
    WheelAngle(i16) = I16, exp10 -4, unit "rad", raw -31_416, 31_416
);
wire_scalar!(
    /// Joint angular velocity. 1e-3 rad/s, `i16` (±32.767 rad/s).
    JointVelocity(i16) = I16, exp10 -3, unit "rad/s", raw i16::MIN, i16::MAX
);
wire_scalar!(
    /// Wheel angular velocity. 1e-2 rad/s, `i16` (±327.67 rad/s).
    WheelVelocity(i16) = I16, exp10 -2, unit "rad/s", raw i16::MIN, i16::MAX
);
wire_scalar!(
    /// Torque of a joint or wheel. 1e-2 N·m, `i16` (±327.67 N·m).
    Torque(i16) = I16, exp10 -2, unit "N.m", raw i16::MIN, i16::MAX
);
wire_scalar!(
    /// Angular rate from the gyro. 1e-3 rad/s, `i16` (±32.767 rad/s: holds the IMU chip's
    /// ±1000 °/s, and a step is a quarter of its noise).
    AngularRate(i16) = I16, exp10 -3, unit "rad/s", raw i16::MIN, i16::MAX
);
wire_scalar!(
    /// Specific force from the accelerometer. 1e-2 m/s², `i16` (±327.67 m/s², ±33 g: holds the
    /// IMU chip's ±6 g, and a step is under half its noise).
    Acceleration(i16) = I16, exp10 -2, unit "m/s^2", raw i16::MIN, i16::MAX
);
wire_scalar!(
    /// Body height offset from the nominal stance height — the report's elevator range.
    /// 1e-4 m, `i16`, accepted −1000…1200 (−0.10…+0.12 m).
    BodyHeight(i16) = I16, exp10 -4, unit "m", raw -1_000, 1_200
);
wire_scalar!(
    /// Speed scale of the commanded motion. 1 %, `u8`, accepted 0…100.
    SpeedScale(u8) = U8, exp10 0, unit "%", raw 0, 100
);
wire_scalar!(
    /// Commanded ground speed of the body, + forward. 1e-3 m/s, `i16`, accepted −2000…2000
    /// (±2 m/s: past what the robot reaches on the wheels; the controller clamps to its own
    /// limits).
    GroundSpeed(i16) = I16, exp10 -3, unit "m/s", raw -2_000, 2_000
);
wire_scalar!(
    /// Commanded yaw rate of the body, + turning left (counter-clockwise seen from above).
    /// 1e-3 rad/s, `i16`, accepted −3000…3000 (±3 rad/s; the controller clamps to its own
    /// limits).
    YawRate(i16) = I16, exp10 -3, unit "rad/s", raw -3_000, 3_000
);
wire_scalar!(
    /// Distance measured by a rangefinder. 1e-3 m, `u16`, accepted 0…4000 (0…4 m: the
    /// VL53L1X's longest range; it reports whole millimetres).
    RangeDistance(u16) = U16, exp10 -3, unit "m", raw 0, 4_000
);
wire_scalar!(
    /// Control tick count. 1 tick, `u32`; wraps after 2^32 ticks (49.7 days at 1 kHz).
    Tick(u32) = U32, exp10 0, unit "tick", raw 0, u32::MAX
);
wire_scalar!(
    /// Duration or uptime. 1 ms, `u32`.
    Millis(u32) = U32, exp10 0, unit "ms", raw 0, u32::MAX
);
wire_scalar!(
    /// A controller boot ([`crate::session`]): strictly greater at every start. 1, `u32`.
    Epoch(u32) = U32, exp10 0, unit "", raw 0, u32::MAX
);
wire_scalar!(
    /// Time since the controller opened its session ([`crate::session`]), ms, `u32`: the
    /// reference a node places counters against, and what a (re)joining sender starts its
    /// counters at. A session lasts at most 2^32 ms (49.7 days).
    SessionTime(u32) = U32, exp10 -3, unit "s", raw 0, u32::MAX
);
wire_scalar!(
    /// Version of the wire contract ([`crate::session::WIRE_VERSION`]). 1, `u8`.
    WireVersion(u8) = U8, exp10 0, unit "", raw 0, u8::MAX
);
wire_scalar!(
    /// E-stop release token: which latch a release answers. The controller counts the times
    /// it entered its E-stop in this session and publishes the count; a release must echo it.
    /// 1, `u16`, wraps.
    ReleaseToken(u16) = U16, exp10 0, unit "", raw 0, u16::MAX
);
wire_scalar!(
    /// Event counter. 1 event, `u16`, wraps.
    Count(u16) = U16, exp10 0, unit "", raw 0, u16::MAX
);

impl Count {
    /// No events.
    pub const ZERO: Count = Count(0);

    /// Count one more event, wrapping at `u16::MAX`.
    pub const fn increment(self) -> Self {
        Self(self.0.wrapping_add(1))
    }
}

impl Epoch {
    /// The epoch numbered `raw` (every `u32` is one).
    pub const fn new(raw: u32) -> Self {
        Self(raw)
    }

    /// The next epoch, or `None` after the last.
    pub const fn next(self) -> Option<Self> {
        match self.0.checked_add(1) {
            Some(raw) => Some(Self(raw)),
            None => None,
        }
    }
}

impl SessionTime {
    /// `ms` milliseconds into the session.
    pub const fn from_ms(ms: u32) -> Self {
        Self(ms)
    }

    /// Milliseconds into the session.
    pub const fn ms(self) -> u32 {
        self.0
    }
}

impl WireVersion {
    /// The version this build speaks.
    pub const THIS: WireVersion = WireVersion(crate::session::WIRE_VERSION);
}

impl ReleaseToken {
    /// The token numbered `raw`.
    pub const fn new(raw: u16) -> Self {
        Self(raw)
    }

    /// The token after this one, wrapping.
    pub const fn next(self) -> Self {
        Self(self.0.wrapping_add(1))
    }
}

impl Tick {
    /// The next tick, wrapping.
    pub const fn next(self) -> Self {
        Self(self.0.wrapping_add(1))
    }
}

wire_enum!(
    /// Whether a rangefinder's distance holds, with the VL53L1X's codes (its `RangeStatus`).
    RangeStatus {
        /// A target within range: the distance holds.
        Valid = 0 => "Valid",
        /// No return strong enough (nothing within range): the distance means nothing.
        SignalFail = 2 => "SignalFail",
    }
);

wire_enum!(
    /// What an E-stop frame asks for.
    EStopAction {
        /// Stop all drives and latch the stop.
        Latch = 1 => "Latch",
        /// Release a latched stop; the robot stays in STOP until commanded.
        Clear = 2 => "Clear",
    }
);

wire_enum!(
    /// Whether a drive should servo to its command or go torque-free.
    DriveEnable {
        /// Torque-free: the drive applies no torque.
        Disabled = 0 => "Disabled",
        /// The drive follows its command.
        Enabled = 1 => "Enabled",
    }
);

wire_enum!(
    /// Operator request: the report's keys, plus stand and fold.
    TeleopMode {
        /// `X`: stop all motion.
        Stop = 0 => "Stop_X",
        /// `W`: drive forward on the wheels.
        WheelForward = 1 => "WheelForward_W",
        /// `S`: drive backward on the wheels.
        WheelBackward = 2 => "WheelBackward_S",
        /// `A`: rotate in place (differential drive).
        WheelRotate = 3 => "WheelRotate_A",
        /// `L`: trot forward.
        TrotForward = 4 => "TrotForward_L",
        /// `K`: trot backward.
        TrotBackward = 5 => "TrotBackward_K",
        /// Stand on the legs.
        Stand = 6 => "Stand",
        /// Fold the legs and balance on the wheels.
        Fold = 7 => "Fold",
        /// Balance on the wheels at the command's `speed` and `yaw_rate` (a gamepad's sticks).
        Drive = 8 => "Drive",
        /// Trot at the command's `speed` and `yaw_rate`.
        Walk = 9 => "Walk",
        /// `H`: the autonomous hybrid mode. Drive on the wheels, back first, and climb by
        /// itself the steps the wheels cannot roll over.
        Auto = 10 => "Auto_H",
    }
);

wire_enum!(
    /// State of the controller's mode machine, as reported in its status.
    ControllerMode {
        /// Standing still (the report's STOP).
        Stop = 0 => "Stop",
        /// Balancing on the wheels, driving forward.
        WheelForward = 1 => "WheelForward",
        /// Balancing on the wheels, driving backward.
        WheelBackward = 2 => "WheelBackward",
        /// Balancing on the wheels, turning in place.
        WheelRotate = 3 => "WheelRotate",
        /// Trotting forward.
        TrotForward = 4 => "TrotForward",
        /// Trotting backward.
        TrotBackward = 5 => "TrotBackward",
        /// Moving the legs to the fold pose before the wheels drive.
        Folding = 6 => "Folding",
        /// Legs taking the weight before a trot.
        Standing = 7 => "Standing",
        /// Emergency stop, latched until cleared.
        EStop = 8 => "EStop",
        /// A fault stopped the robot.
        Fault = 9 => "Fault",
        /// Balancing on the wheels at the operator's speed and yaw rate.
        Driving = 10 => "Driving",
        /// Trotting at the operator's speed and yaw rate.
        Walking = 11 => "Walking",
        /// Driving on the wheels in the autonomous hybrid mode.
        Auto = 12 => "Auto",
        /// Climbing a step in the autonomous hybrid mode.
        Climbing = 13 => "Climbing",
    }
);

wire_flags!(
    /// Why the controller is not (fully) operating. `u16`, one bit per cause.
    FaultFlags(u16) = U16 {
        /// An E-stop is latched.
        ESTOP_LATCHED = 0 => "estop_latched",
        /// Joint or wheel feedback stopped arriving.
        FEEDBACK_TIMEOUT = 1 => "feedback_timeout",
        /// IMU samples stopped arriving.
        IMU_TIMEOUT = 2 => "imu_timeout",
        /// The operator's heartbeat stopped arriving.
        TELEOP_TIMEOUT = 3 => "teleop_timeout",
        /// The torso tilted past its limit.
        TILT_LIMIT = 4 => "tilt_limit",
        /// A drive reported a fault or a timeout.
        DRIVE_FAULT = 5 => "drive_fault",
        /// The lockstep clock jumped or restarted.
        SYNC_LOST = 6 => "sync_lost",
        /// A computed command was not finite and was replaced by a safe one.
        NON_FINITE = 7 => "non_finite",
        /// The bus loses too many of the controller's inbound frames: motion stops and new
        /// motion requests are refused until the link recovers.
        LINK_DEGRADED = 8 => "link_degraded",
        /// Motion is interlocked (no unexpected start-up): after the controller started, an
        /// E-stop release, or a lost operator, nothing moves until the operator sends STOP
        /// (X) and then a motion.
        AWAITING_STOP = 9 => "awaiting_stop",
        /// The wheels could not follow the speed reference (something blocks them: a step they
        /// cannot climb): the robot was braked and set down.
        WHEEL_STALL = 10 => "wheel_stall",
        /// The robot moved away from the speed reference, or the balance law stayed saturated
        /// (a centre of mass off its trim, a push it cannot take): braked and set down; or it
        /// leaned on its legs while the balance law drove the wheels: the wheels held still.
        RUNAWAY = 11 => "runaway",
        /// The trot's leading feet ended their swings behind where they were sent, swing after
        /// swing (a step or a wall they cannot clear), or, walking backward, the rangefinder saw
        /// the ground behind rise (a riser or a slope ahead of the back feet): the robot stopped
        /// and stands; cleared by the operator's next request.
        LEG_BLOCKED = 12 => "leg_blocked",
        /// The autonomous mode met a step it does not climb (lower than the wheels roll
        /// over, higher than the legs set a foot on, or no ground within their reach): the
        /// robot folded back onto its wheels and balances; cleared by the operator's next
        /// request.
        STEP_REFUSED = 13 => "step_refused",
        /// The autonomous mode heard no ranging from the rangefinder for 0.2 s, or none with a
        /// return over 1.5 m of level ground: it would drive blind toward what it cannot see,
        /// so the robot stopped and balances; cleared by the operator's next request.
        RANGE_TIMEOUT = 14 => "range_timeout",
        /// A stand-up from the wheels left the torso on its legs pitched past 15° for a
        /// second (front legs at their rating that gave way, or back legs at their shallowest
        /// that cannot level it): nothing moves for the report (the stand's own levelling goes
        /// on). The operator's next request clears it; a stand still tilted a second later
        /// raises it again. The last free bit: a further flag needs a wider field (a new wire
        /// version).
        STAND_TILTED = 15 => "stand_tilted",
    }
);

wire_flags!(
    /// State of a drive. `u8`, one bit per condition.
    DriveFlags(u8) = U8 {
        /// The drive applies torque.
        ENABLED = 0 => "enabled",
        /// No valid command arrived within the command timeout; torque is off.
        TIMED_OUT = 1 => "timed_out",
        /// The drive detected a fault (over-limit, over-temperature, …); torque is off.
        FAULT = 2 => "fault",
        /// The drive saw an E-stop and stays torque-free until it is cleared.
        ESTOP = 3 => "estop",
        /// Since its last status the drive cut a torque to its rating (peak, torque-speed
        /// limit or thermal foldback).
        SATURATED = 4 => "saturated",
    }
);
