//! Every tunable of the controller in one value, with the report's numbers as defaults.

use crate::control::estimator::EstimatorConfig;
use crate::control::heading::HeadingConfig;
use crate::control::steering::SteeringConfig;
use crate::control::stop::StopConfig;
use crate::control::terrain::rise::RiseConfig;
use crate::control::terrain::TerrainConfig;
use crate::legs::blocked::BlockedConfig;
use crate::legs::climb::ClimbConfig;
use crate::legs::gait::TrotParams;
use crate::legs::kinematics::LegGeometry;
use crate::legs::levelling::LevellingConfig;
use crate::legs::posture::Posture;
use crate::legs::smoothing::Smoother;
use crate::legs::support::SupportGeometry;
use crate::legs::transfer::TransferConfig;
use crate::limits::JointLimits;
use crate::time::TickRate;
use crate::wheels::balance::{BalanceConfig, BalanceGains, BalanceModel};
use crate::wheels::lean::LeanConfig;
use crate::wheels::runaway::RunawayConfig;
use crate::wheels::traction::TractionConfig;
use crate::wheels::wheel::SpeedLoopGains;

/// Controller configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Control rate.
    pub rate: TickRate,
    /// Leg links.
    pub geometry: LegGeometry,
    /// Joint ranges.
    pub limits: JointLimits,
    /// Stance poses.
    pub posture: Posture,
    /// The fold poses, and how the legs level the robot on its wheels.
    pub levelling: LevellingConfig,
    /// What touches the ground: when the wheels may be driven.
    pub support: SupportGeometry,
    /// Trot.
    pub trot: TrotParams,
    /// Leg smoothing rate, 1/s (the report's 8).
    pub leg_rate_per_s: f32,
    /// Smoothing rate while trotting, 1/s. The report's 8 /s lags a 1 Hz gait by 38° and
    /// shrinks it to 79 %, and the lag is not symmetric in time: a trot run backward through it
    /// lifted its feet at the wrong end of the stride and did not move (measured in the
    /// simulator). A fast rate keeps only the smoothing of the step into the gait.
    pub gait_rate_per_s: f32,
    /// Smoothing rate that holds the fold on the wheels, 1/s (the report's 6).
    pub fold_rate_per_s: f32,
    /// The fold from the legs onto the wheels.
    pub transfer: TransferConfig,
    /// A transition ends when every smoothed target is this close to its pose, rad.
    pub pose_tolerance_rad: f32,
    /// Wheel speed of W/S and of each wheel in A (the report's 4 rad/s).
    pub wheel_speed_rad_s: f32,
    /// Steering: the wheel track and the yaw-rate limits.
    pub steering: SteeringConfig,
    /// The trot's heading hold.
    pub heading: HeadingConfig,
    /// Per-wheel torque limit, N·m.
    pub wheel_torque_limit_nm: f32,
    /// Turn (differential) speed loop.
    pub turn: SpeedLoopGains,
    /// Balance law.
    pub balance: BalanceConfig,
    /// Leg or wheel feedback older than this stops the robot, ms. The watchdog trips on the
    /// first tick past it, so 40 ms makes the safe stop come within 50 ms of the last frame at
    /// 250 Hz (44 ms: 11 ticks) and at 1 kHz (41 ms).
    pub feedback_timeout_ms: u32,
    /// IMU samples older than this stop a balancing robot, ms (40, as the drives' feedback).
    pub imu_timeout_ms: u32,
    /// An operator silent this long is treated as a stop request, ms. 460 ms so that the robot
    /// is stopped within 500 ms of teleop dying: its last heartbeat may have gone out up to one
    /// 20 ms period before, and the watchdog acts on the next 4 ms tick.
    pub teleop_timeout_ms: u32,
    /// Length of one window of the link monitor, ms: the inbound loss ratio is judged once per
    /// window (see [`crate::node::link`]). 1 s holds well over a thousand frames at 250 Hz, so 10 %
    /// loss stands far above the count's noise at 5 %, and a lossy link is stopped within two
    /// windows of the loss starting.
    pub link_window_ms: u32,
    /// A window that loses more than this share of the frames sent to the controller degrades
    /// the link: the robot stops and refuses new motion, ‰ (100 = 10 %). At 20 % loss one
    /// operator command in five is gone, and E-stop clears or stop keys may need repeating.
    pub link_degrade_permille: u32,
    /// A window that loses at most this share recovers the link, ‰ (30 = 3 %). Below the
    /// degrade threshold so that a loss ratio near either one does not make the state flicker.
    pub link_recover_permille: u32,
    /// Pitch or roll beyond this is a fall: fault, rad.
    pub tilt_limit_rad: f32,
    /// The attitude filter on the IMU's gyro and accelerometer.
    pub attitude: EstimatorConfig,
    /// The E-stop's controlled stop (within [`crate::control::safety::SS1_DEADLINE_MS`]),
    /// also run when the wheels stall or run away.
    pub stop: StopConfig,
    /// When the wheels count as stalled or running away.
    pub runaway: RunawayConfig,
    /// When the wheels count as off the ground, and how they hold meanwhile.
    pub traction: TractionConfig,
    /// When a lean says the robot rests on something other than its wheels.
    pub lean: LeanConfig,
    /// When the trot counts as blocked by what it cannot step over.
    pub blocked: BlockedConfig,
    /// How the autonomous mode climbs a step its wheels stall against
    /// ([`crate::legs::climb`]; `None`: the stall is a fault, as in the manual modes).
    pub climb: Option<ClimbConfig>,
    /// Where the rangefinder sits and how its rangings are read
    /// ([`crate::control::terrain`]).
    pub terrain: TerrainConfig,
    /// When a backward trot sees the ground behind rise
    /// ([`crate::control::terrain::rise`]).
    pub rise: RiseConfig,
}

/// Per-wheel torque limit of the robot, N·m.
const WHEEL_TORQUE_LIMIT_NM: f32 = 30.0;

impl Config {
    /// The robot at 250 Hz (one tick per simulator step of 0.004 s).
    pub const ROBOT: Self = Self {
        rate: TickRate::SIM_250_HZ,
        geometry: LegGeometry::ROBOT,
        limits: JointLimits::REPORT,
        posture: Posture::ROBOT,
        levelling: LevellingConfig::ROBOT,
        support: SupportGeometry::ROBOT,
        trot: TrotParams::DEFAULT,
        leg_rate_per_s: Smoother::LEG_RATE_PER_S,
        gait_rate_per_s: 50.0,
        fold_rate_per_s: Smoother::FOLD_RATE_PER_S,
        transfer: TransferConfig::ROBOT,
        pose_tolerance_rad: 0.01,
        wheel_speed_rad_s: 4.0,
        steering: SteeringConfig::ROBOT,
        heading: HeadingConfig::ROBOT,
        wheel_torque_limit_nm: WHEEL_TORQUE_LIMIT_NM,
        turn: SpeedLoopGains::TURN,
        balance: BalanceConfig {
            gains: BalanceGains::ROBOT,
            wheel_radius_m: BalanceModel::ROBOT.wheel_radius_m,
            torque_limit_nm: 2.0 * WHEEL_TORQUE_LIMIT_NM,
            position_error_limit_m: 0.3,
            pitch_trim_rad: crate::math::deg_to_rad(1.4),
            trim_time_constant_s: 2.0,
            trim_range_rad: crate::math::deg_to_rad(15.0),
            trim_follow_time_constant_s: 0.1,
            lean_rad_per_m_s2: BalanceModel::ROBOT.lean_rad_per_m_s2(),
            accel_limit_m_s2: 0.35,
            brake_limit_m_s2: 1.2,
            wheel_viscous_nm_per_rad_s: 2.0,
        },
        feedback_timeout_ms: 40,
        imu_timeout_ms: 40,
        teleop_timeout_ms: 460,
        link_window_ms: 1_000,
        link_degrade_permille: 100,
        link_recover_permille: 30,
        tilt_limit_rad: crate::math::deg_to_rad(45.0),
        attitude: EstimatorConfig::ROBOT,
        stop: StopConfig::ROBOT,
        runaway: RunawayConfig::ROBOT,
        traction: TractionConfig::ROBOT,
        lean: LeanConfig::ROBOT,
        blocked: BlockedConfig::ROBOT,
        climb: Some(ClimbConfig::ROBOT),
        terrain: TerrainConfig::ROBOT,
        rise: RiseConfig::ROBOT,
    };

    /// This configuration at another control rate (gains are per second, so only the tick
    /// arithmetic changes).
    pub const fn at_rate(self, rate: TickRate) -> Self {
        Self { rate, ..self }
    }
}
