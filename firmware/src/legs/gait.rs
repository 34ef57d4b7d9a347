//! The trot: diagonal pairs FL+BR and FR+BL half a cycle apart (report section 6.3), driven by
//! an integer [`Phase`] so the gait after ten hours is the gait after ten seconds.
//!
//! Walking backward runs the phase backward in time. (The report's `leg_backward` only swapped
//! which pair leads, which is the forward gait shifted by half a cycle: its robot could not
//! have walked backward.)

use protocol::Leg;

use crate::attitude::Attitude;
use crate::control::fsm::Direction;
use crate::legs::foot_trajectory::FootTrajectory;
use crate::legs::hips::HipLayout;
use crate::legs::kinematics::{IkError, LegGeometry, LegJoints};
use crate::legs::phase::{Phase, PhaseStep, HALF_CYCLE};
use crate::legs::posture::Posture;
use crate::legs::sine_gait::SineGait;
use crate::limits::JointLimits;
use crate::time::TickRate;

/// Which foot-motion generator drives the trot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Generator {
    /// The report's joint-space sinusoids (reproduction).
    Sine(SineGait),
    /// Stance line and swing arc through the IK (the default walking gait).
    Cartesian(FootTrajectory),
}

/// How the stance legs keep the trotting body level in roll: the stance lines of the legs on
/// the low side go deeper by `roll_m_per_rad · |roll|` and those on the high side shallower,
/// within `limit_m` and the trot's reach (at the nominal body height the stance line cannot
/// rise above [`Posture::trot_depth_min_m`], so only the low side pushes; with the body raised
/// to the deepest stance, only the high side lifts). A trot on low friction slipped, rolled
/// onto a lateral pair of feet and fell (the campaign's L: 104 of 500 runs fell, 65 % of those
/// drawn at friction 0.6–0.8). Measured over 500 trials: L 67.0 → 83.0 %, K 64.8 → 75.0 %,
/// X after L 93.2 → 87.8 %; 0.2 m/rad oscillated (L 81, K 52 % over 100), and levelling pitch
/// too, or stepping ahead by the pitch, measured worse. Since the feet stand 55 % of the cycle
/// ([`FootTrajectory::duty`]) the body rocks less and 0.05 m/rad serves: at 0.1 the trot
/// rolled onto two feet of one side at the changes of support (K 90 → 97 %, L, K and X after
/// L 287 → 296 of 300 runs over 100 trials; 0, 0.03 and 0.07 measured within a run of 0.05).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyLevel {
    /// Stance depth per rad of roll, m/rad.
    pub roll_m_per_rad: f32,
    /// Largest change of a stance line, m.
    pub limit_m: f32,
}

impl BodyLevel {
    /// Off: the stance lines stay where the gait puts them.
    pub const OFF: Self = Self {
        roll_m_per_rad: 0.0,
        limit_m: 0.0,
    };

    /// How much deeper `leg`'s stance line goes for `attitude`, m (0 for a non-finite one).
    pub fn depth_offset_m(&self, leg: Leg, attitude: &Attitude) -> f32 {
        // Roll positive lifts the left side: the right legs push.
        let side = if matches!(leg, Leg::Fr | Leg::Br) {
            1.0
        } else {
            -1.0
        };
        let offset = self.roll_m_per_rad * side * attitude.roll_rad;
        if offset.is_finite() {
            crate::math::clamp(offset, -self.limit_m, self.limit_m)
        } else {
            0.0
        }
    }
}

/// Trot settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrotParams {
    /// Stride frequency, mHz (the report's 1 Hz = 1000).
    pub frequency_millihz: u32,
    /// Foot-motion generator.
    pub generator: Generator,
    /// How the stance legs level the body (the Cartesian generator only).
    pub body_level: BodyLevel,
    /// Where the legs attach: a turning trot strides each foot along its hip's path.
    pub hips: HipLayout,
}

/// What the trot's stance feet carry the body at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrotCommand {
    /// Speed in the trot's direction as a share of the full stride's speed (0…1).
    pub stride_share: f32,
    /// Yaw rate, rad/s, + turning left (the Cartesian generator only).
    pub yaw_rate_rad_s: f32,
}

impl TrotCommand {
    /// Straight on at `stride_share` of the full stride.
    pub const fn straight(stride_share: f32) -> Self {
        Self {
            stride_share,
            yaw_rate_rad_s: 0.0,
        }
    }

    /// Whether the body travels along the trot's direction (a trot at no speed marks time).
    pub fn advances(&self) -> bool {
        self.stride_share > 0.0
    }

    /// Whether the feet lift and stride: travelling, or turning on the spot (the Cartesian
    /// generator; the report's sine gait does not turn).
    pub fn lifts_feet(&self) -> bool {
        self.advances() || (self.yaw_rate_rad_s.is_finite() && self.yaw_rate_rad_s != 0.0)
    }
}

/// One leg's stride in a trot, as shares of the full stride (the foot path's length), in the
/// trot's direction: `along` fore–aft, `across` to the left.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegStride {
    /// Fore–aft share.
    pub along: f32,
    /// Sideways share.
    pub across: f32,
}

impl TrotParams {
    /// The default walking gait: 1 Hz, Cartesian foot path.
    pub const DEFAULT: Self = Self {
        frequency_millihz: 1000,
        generator: Generator::Cartesian(FootTrajectory::DEFAULT),
        body_level: BodyLevel {
            roll_m_per_rad: 0.05,
            limit_m: 0.02,
        },
        hips: HipLayout::ROBOT,
    };
    /// The report's gait: 1 Hz joint-space sinusoids.
    pub const REPORT: Self = Self {
        frequency_millihz: 1000,
        generator: Generator::Sine(SineGait::REPORT),
        body_level: BodyLevel::OFF,
        hips: HipLayout::ROBOT,
    };
}

/// Phase offset of a leg within the trot: FL and BR lead, FR and BL follow half a cycle later.
pub const fn pair_offset(leg: Leg) -> u32 {
    match leg {
        Leg::Fl | Leg::Br => 0,
        Leg::Fr | Leg::Bl => HALF_CYCLE,
    }
}

/// A running trot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trot {
    params: TrotParams,
    step: PhaseStep,
    phase: Phase,
}

impl Trot {
    /// `None` if the frequency is zero or not below the tick rate.
    pub const fn new(params: TrotParams, rate: TickRate) -> Option<Self> {
        match PhaseStep::new(params.frequency_millihz, rate) {
            Some(step) => Some(Self {
                params,
                step,
                phase: Phase::from_count(0),
            }),
            None => None,
        }
    }

    /// Back to the start of a cycle.
    pub fn restart(&mut self) {
        self.phase = Phase::default();
    }

    /// One tick forward.
    pub fn advance(&mut self) {
        self.phase.advance(self.step);
    }

    /// The cycle phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Sets the cycle phase (for tests and replays).
    pub fn set_phase(&mut self, phase: Phase) {
        self.phase = phase;
    }

    /// The phase step per tick.
    pub fn step(&self) -> PhaseStep {
        self.step
    }

    /// The phase `leg` sees when walking in `direction`.
    pub fn leg_phase(&self, leg: Leg, direction: Direction) -> Phase {
        let base = match direction {
            Direction::Forward => self.phase,
            Direction::Backward => self.phase.reversed(),
        };
        base.shifted(pair_offset(leg))
    }

    /// How far `leg`'s foot is through its swing now, walking in `direction` (0 at lift-off,
    /// toward 1 at touchdown), or `None` while it stands: the swing is the cycle past the
    /// stance share ([`FootTrajectory::duty`]). The report's sinusoids have no swing of that
    /// shape (their hips sweep forward across the cycle's turn): `None` throughout.
    pub fn swing_share(&self, leg: Leg, direction: Direction) -> Option<f32> {
        let duty = match self.params.generator {
            Generator::Cartesian(path) => crate::math::clamp(path.duty, 0.5, 0.9),
            Generator::Sine(_) => return None,
        };
        let fraction = self.leg_phase(leg, direction).fraction();
        // Walking backward the phase runs backward: the swing is traversed from its end.
        (fraction >= duty).then(|| {
            let share = (fraction - duty) / (1.0 - duty);
            match direction {
                Direction::Forward => share,
                Direction::Backward => 1.0 - share,
            }
        })
    }

    /// The body speed of the full stride, m/s: a stance carries the foot one stride length in
    /// the duty's share of the cycle (`None` for the report's sinusoids, which have no stride
    /// in metres).
    pub fn full_speed_m_s(&self) -> Option<f32> {
        match self.params.generator {
            Generator::Cartesian(path) => {
                let duty = crate::math::clamp(path.duty, 0.5, 0.9);
                let frequency_hz = self.params.frequency_millihz as f32 * 1e-3;
                Some(path.step_length_m * frequency_hz / duty)
            }
            Generator::Sine(_) => None,
        }
    }

    /// Every leg's stride for `command` walking in `direction`, in [`Leg::ALL`] order. A yaw
    /// rate ω moves each hip at `(v − ω·y, ω·x)` over the ground; its foot strides against
    /// that. When a leg would need more than the full stride, all strides shrink alike, so that
    /// the turn keeps its radius.
    pub fn strides(&self, direction: Direction, command: &TrotCommand) -> [LegStride; 4] {
        let share = crate::math::clamp(command.stride_share, 0.0, 1.0);
        let turn = match self.full_speed_m_s() {
            Some(full) if command.yaw_rate_rad_s.is_finite() => command.yaw_rate_rad_s / full,
            _ => 0.0,
        };
        // Walking backward the phase runs backward, and with it the stride's sense.
        let sign = match direction {
            Direction::Forward => 1.0,
            Direction::Backward => -1.0,
        };
        let strides = Leg::ALL.map(|leg| {
            let (x_m, y_m) = self.params.hips.offset_m(leg);
            LegStride {
                along: if share.is_nan() { 0.0 } else { share } - sign * turn * y_m,
                across: sign * turn * x_m,
            }
        });
        let longest = strides.iter().fold(0.0_f32, |most, stride| {
            most.max(crate::math::sqrt(
                stride.along * stride.along + stride.across * stride.across,
            ))
        });
        if longest > 1.0 {
            strides.map(|stride| LegStride {
                along: stride.along / longest,
                across: stride.across / longest,
            })
        } else {
            strides
        }
    }

    /// `leg`'s stride for `command` walking in `direction` (see [`Trot::strides`]).
    pub fn stride(&self, leg: Leg, direction: Direction, command: &TrotCommand) -> LegStride {
        stride_of(&self.strides(direction, command), leg)
    }

    /// Joint targets of all four legs (in [`Leg::ALL`] order) at the present phase, for a
    /// stance `depth_m` below the hips, the stride `command` asks for and the body at
    /// `attitude` ([`BodyLevel`]).
    #[allow(clippy::too_many_arguments)]
    pub fn targets(
        &self,
        direction: Direction,
        depth_m: f32,
        command: &TrotCommand,
        attitude: &Attitude,
        geometry: &LegGeometry,
        limits: &JointLimits,
        posture: &Posture,
    ) -> [Result<LegJoints, IkError>; 4] {
        let strides = self.strides(direction, command);
        Leg::ALL.map(|leg| {
            let stride = stride_of(&strides, leg);
            let phase = self.leg_phase(leg, direction);
            match self.params.generator {
                Generator::Sine(sine) => Ok(sine.joints(phase, command.stride_share)),
                Generator::Cartesian(path) => {
                    let level_m = self.params.body_level.depth_offset_m(leg, attitude);
                    // Within the trot's reach: the swing arc rises above the stance line.
                    let leg_depth_m = crate::math::clamp(
                        depth_m + level_m,
                        posture.trot_depth_min_m,
                        posture.depth_max_m,
                    );
                    let foot = path.foot_on_stride(phase, leg_depth_m, stride.along, stride.across);
                    posture.foot_ik_at(geometry, limits, foot.x_m, foot.y_m, -foot.z_m)
                }
            }
        })
    }
}

/// `leg`'s entry of `strides` (in [`Leg::ALL`] order).
const fn stride_of(strides: &[LegStride; 4], leg: Leg) -> LegStride {
    let [fl, fr, bl, br] = *strides;
    match leg {
        Leg::Fl => fl,
        Leg::Fr => fr,
        Leg::Bl => bl,
        Leg::Br => br,
    }
}
