//! What a user checks after a run, per segment of a scenario, from the simulator's ground
//! truth: how far and which way the robot went, how much it tilted, whether it fell, whether a
//! joint or torque went past its limit, what touched the ground, and the bus traffic.

use protocol::ControllerMode;
use serde::Serialize;

use crate::output::crossings::{Crossing, CrossingTracker};
use crate::output::decimated::Decimated;
use crate::output::torques::{TorqueFigures, TorqueTracker};
use crate::scene::Feature;
use crate::session::simulator::Simulator;

/// A joint counts as past its limit beyond this, rad (MuJoCo's limits are soft constraints:
/// a loaded joint presses a fraction of a degree into them).
pub const JOINT_TOLERANCE_RAD: f64 = 0.0175;
/// The robot has stopped once its torso stays this close to where it ends, m (a legged robot
/// sways on its servos after it stops walking; a balancing one rocks on its wheels).
pub const STOPPED_RADIUS_M: f64 = 0.03;
/// … and its heading this close to its final heading, degrees.
pub const STOPPED_YAW_DEG: f64 = 3.0;
/// Tilt beyond which the robot has fallen, degrees (the controller's own limit).
pub const FALLEN_TILT_DEG: f64 = 45.0;
/// Foot load that counts as contact, N.
pub const FOOT_CONTACT_N: f64 = 20.0;

/// Frames seen on the bus, cumulative.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct BusCounters {
    /// Frames the simulator sent.
    pub frames_sent: u64,
    /// Frames the simulator received.
    pub frames_received: u64,
    /// Frames the firmware rejected, by cause, in [`protocol::RejectCause::ALL`] order: unknown
    /// id, wrong length, CRC, out of range, repeated, wrong sequence, rate limited.
    pub firmware_rejected: [u64; protocol::RejectCause::ALL.len()],
    /// Frames the firmware found missing from sequences.
    pub firmware_lost: u64,
    /// Frames the drives rejected.
    pub drives_rejected: u64,
    /// Lockstep cycles whose command came late.
    pub missed_cycles: u64,
}

impl BusCounters {
    fn since(&self, start: &BusCounters) -> BusCounters {
        BusCounters {
            frames_sent: self.frames_sent - start.frames_sent,
            frames_received: self.frames_received - start.frames_received,
            firmware_rejected: std::array::from_fn(|i| {
                self.firmware_rejected[i] - start.firmware_rejected[i]
            }),
            firmware_lost: self.firmware_lost - start.firmware_lost,
            drives_rejected: self.drives_rejected - start.drives_rejected,
            missed_cycles: self.missed_cycles - start.missed_cycles,
        }
    }
}

/// One segment's figures (serialised into `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentSummary {
    /// Segment name.
    pub label: String,
    /// Commanded mode: W S A L K X, stand, fold.
    pub mode: String,
    /// Start, s.
    pub start_s: f64,
    /// End, s.
    pub end_s: f64,
    /// Torso displacement in the world frame, m.
    pub dx_m: f64,
    /// Torso displacement in the world frame, m.
    pub dy_m: f64,
    /// Displacement along the torso's heading at the segment start (+ = forward), m.
    pub forward_m: f64,
    /// Displacement across that heading (+ = left), m.
    pub lateral_m: f64,
    /// Yaw change, unwrapped, degrees (+ = left).
    pub dyaw_deg: f64,
    /// Largest torso tilt (angle of its up axis from vertical), degrees.
    pub max_tilt_deg: f64,
    /// Largest |roll|, degrees.
    pub max_roll_deg: f64,
    /// Largest |pitch|, degrees.
    pub max_pitch_deg: f64,
    /// Lowest torso-centre height, m.
    pub min_height_m: f64,
    /// Torso height at the end, m.
    pub end_height_m: f64,
    /// Whether the robot fell (tilt past 45° or the torso on the ground).
    pub fell: bool,
    /// Cycles with a leg joint more than 1° past its range.
    pub joint_limit_violations: u64,
    /// Largest excess of a leg joint past its range, degrees (0 inside).
    pub max_joint_excess_deg: f64,
    /// Cycles with a wheel torque past the limit.
    pub torque_limit_violations: u64,
    /// Largest applied wheel torque, N·m.
    pub max_wheel_torque_nm: f64,
    /// Peak and RMS torques of the joints and wheels, and the drives' saturation.
    pub torques: TorqueFigures,
    /// Cycles in which a foot or a body part touched the ground.
    pub feet_or_body_on_ground_cycles: u64,
    /// Cycles in which a body part (torso, leg link) touched the ground.
    pub body_on_ground_cycles: u64,
    /// Cycles in which the torso box touched the ground.
    pub torso_on_ground_cycles: u64,
    /// Cycles in which exactly two feet carried the robot and they were not a diagonal pair
    /// (not a trot's support).
    pub non_diagonal_support_cycles: u64,
    /// Cycles in the segment.
    pub cycles: u64,
    /// Time from the segment start after which the torso stayed within 3 cm and 3° of where it
    /// ended: when the robot stopped. `None` if it was still moving at the end (the last tenth
    /// of a second left that band).
    pub settled_after_s: Option<f64>,
    /// Largest distance of the torso, from 1 s into the segment on, from where it was at 1 s,
    /// m: how far a robot told to stop still goes after the first second.
    pub moved_after_1s_m: f64,
    /// Bus traffic in the segment.
    pub bus: BusCounters,
    /// Which parts of the robot touched which obstacle of the scene (not the floor), and for
    /// how many cycles, in the order first seen: a step's riser met by the feet, the shanks,
    /// the wheels or the torso.
    pub obstacle_contacts: Vec<ObstacleContact>,
    /// For each obstacle of the scene: when a foot first stood on it, when all four did, when
    /// all four were past it, and how long that took.
    pub crossings: Vec<Crossing>,
    /// The controller's climbs in the segment: each climb's time from the status reporting
    /// `Climbing` to the status leaving it, s (the last one up to the segment's end if it
    /// still climbs).
    pub climbs_s: Vec<f64>,
}

/// A part of the robot touching an obstacle in a segment.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct ObstacleContact {
    /// The obstacle's geom (`step`, `ramp_up`, `flight_up_1`, …).
    pub obstacle: String,
    /// The robot's geom (`foot_fl`, `shank_fr`, `wheel_left`, `torso`, …).
    pub part: String,
    /// Cycles in which they touched.
    pub cycles: u64,
}

/// Accumulates a segment's figures cycle by cycle.
#[derive(Debug, Clone)]
pub struct SegmentTracker {
    summary: SegmentSummary,
    start_pos: [f64; 3],
    start_yaw: f64,
    last_yaw: f64,
    start_bus: BusCounters,
    limits: [(f64, f64); 4],
    wheel_limit_nm: f64,
    torques: TorqueTracker,
    /// (time s, x m, y m, unwrapped yaw deg) of every cycle (of fewer in a segment longer
    /// than 4.4 simulated minutes: bounded memory).
    track: Decimated<(f64, f64, f64, f64)>,
    /// The geom ids of each entry of `summary.obstacle_contacts`, and the cycle it was last
    /// counted in (a pair touches at several points).
    contact_ids: Vec<((usize, usize), u64)>,
    crossings: CrossingTracker,
    /// When the climb under way began, s (`None`: no climb).
    climb_since_s: Option<f64>,
}

impl SegmentTracker {
    /// Starts a segment on the simulator's present state, in a scene with `obstacles`.
    pub fn start(
        label: &str,
        mode: &str,
        sim: &Simulator,
        bus: BusCounters,
        obstacles: &[Feature],
    ) -> Self {
        let config = firmware::config::Config::ROBOT;
        let limits = config
            .limits
            .ranges
            .map(|r| (f64::from(r.min_rad), f64::from(r.max_rad)));
        let torso = sim.physics().torso();
        let yaw = torso.rpy_rad()[2];
        Self {
            summary: SegmentSummary {
                label: label.to_owned(),
                mode: mode.to_owned(),
                start_s: sim.time_s(),
                end_s: sim.time_s(),
                dx_m: 0.0,
                dy_m: 0.0,
                forward_m: 0.0,
                lateral_m: 0.0,
                dyaw_deg: 0.0,
                max_tilt_deg: 0.0,
                max_roll_deg: 0.0,
                max_pitch_deg: 0.0,
                min_height_m: torso.pos_m[2],
                end_height_m: torso.pos_m[2],
                fell: false,
                joint_limit_violations: 0,
                max_joint_excess_deg: 0.0,
                torque_limit_violations: 0,
                max_wheel_torque_nm: 0.0,
                torques: TorqueFigures::default(),
                feet_or_body_on_ground_cycles: 0,
                body_on_ground_cycles: 0,
                torso_on_ground_cycles: 0,
                non_diagonal_support_cycles: 0,
                cycles: 0,
                settled_after_s: None,
                moved_after_1s_m: 0.0,
                bus: BusCounters::default(),
                obstacle_contacts: Vec::new(),
                crossings: Vec::new(),
                climbs_s: Vec::new(),
            },
            start_pos: torso.pos_m,
            start_yaw: yaw,
            last_yaw: yaw,
            start_bus: bus,
            limits,
            wheel_limit_nm: f64::from(config.wheel_torque_limit_nm),
            torques: TorqueTracker::start(sim),
            track: Decimated::default(),
            contact_ids: Vec::new(),
            crossings: CrossingTracker::start(obstacles, sim),
            climb_since_s: None,
        }
    }

    /// Takes one cycle's state.
    pub fn observe(&mut self, sim: &Simulator, bus: BusCounters) {
        let s = &mut self.summary;
        let physics = sim.physics();
        let torso = physics.torso();
        let [roll, pitch, yaw] = torso.rpy_rad();
        let step = (yaw - self.last_yaw + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        self.last_yaw = yaw;
        s.dyaw_deg += step.to_degrees();
        let climbing = sim.hardware().controller_mode() == Some(ControllerMode::Climbing);
        match (climbing, self.climb_since_s) {
            (true, None) => {
                self.climb_since_s = Some(sim.time_s());
                s.climbs_s.push(0.0);
            }
            (false, Some(_)) => self.climb_since_s = None,
            _ => {}
        }
        if let (Some(since_s), Some(last)) = (self.climb_since_s, s.climbs_s.last_mut()) {
            *last = sim.time_s() - since_s;
        }
        s.end_s = sim.time_s();
        s.cycles += 1;
        let dx = torso.pos_m[0] - self.start_pos[0];
        let dy = torso.pos_m[1] - self.start_pos[1];
        s.dx_m = dx;
        s.dy_m = dy;
        let (sin_h, cos_h) = self.start_yaw.sin_cos();
        s.forward_m = dx * cos_h + dy * sin_h;
        s.lateral_m = -dx * sin_h + dy * cos_h;
        let tilt = torso.tilt_rad().to_degrees();
        s.max_tilt_deg = s.max_tilt_deg.max(tilt);
        s.max_roll_deg = s.max_roll_deg.max(roll.to_degrees().abs());
        s.max_pitch_deg = s.max_pitch_deg.max(pitch.to_degrees().abs());
        s.min_height_m = s.min_height_m.min(torso.pos_m[2]);
        s.end_height_m = torso.pos_m[2];
        let contacts = physics.ground_contacts();
        s.fell |= tilt > FALLEN_TILT_DEG || contacts.torso;
        let mut excess: f64 = 0.0;
        for (_, angles) in physics.leg_positions_rad().iter_legs() {
            for (angle, (lo, hi)) in angles.iter().zip(self.limits) {
                excess = excess.max(lo - angle).max(angle - hi);
            }
        }
        s.max_joint_excess_deg = s.max_joint_excess_deg.max(excess.max(0.0).to_degrees());
        if excess > JOINT_TOLERANCE_RAD {
            s.joint_limit_violations += 1;
        }
        let torque = sim.hardware().wheel_torque_nm();
        let largest = torque.iter().fold(0.0_f64, |m, t| m.max(t.abs()));
        s.max_wheel_torque_nm = s.max_wheel_torque_nm.max(largest);
        if largest > self.wheel_limit_nm + 1e-6 {
            s.torque_limit_violations += 1;
        }
        self.torques.observe(sim);
        let loaded = physics.foot_forces_n().map(|f| f > FOOT_CONTACT_N);
        if loaded.iter().any(|l| *l) || contacts.other {
            s.feet_or_body_on_ground_cycles += 1;
        }
        if contacts.other {
            s.body_on_ground_cycles += 1;
        }
        if contacts.torso {
            s.torso_on_ground_cycles += 1;
        }
        let [fl, fr, bl, br] = loaded;
        let feet_down = loaded.iter().filter(|l| **l).count();
        let diagonal = (fl && br) || (fr && bl);
        if feet_down == 2 && !diagonal {
            s.non_diagonal_support_cycles += 1;
        }
        self.track
            .push((sim.time_s(), torso.pos_m[0], torso.pos_m[1], s.dyaw_deg));
        s.bus = bus.since(&self.start_bus);
        self.count_obstacle_contacts(sim);
        self.crossings.observe(sim);
    }

    /// Counts this cycle's contacts with obstacles, each pair once.
    fn count_obstacle_contacts(&mut self, sim: &Simulator) {
        let physics = sim.physics();
        let cycle = self.summary.cycles;
        for pair in physics.obstacle_contacts() {
            let index = match self.contact_ids.iter().position(|(ids, _)| *ids == pair) {
                Some(index) => index,
                None => {
                    self.contact_ids.push((pair, 0));
                    self.summary.obstacle_contacts.push(ObstacleContact {
                        obstacle: physics.geom_name(pair.0).to_owned(),
                        part: physics.geom_name(pair.1).to_owned(),
                        cycles: 0,
                    });
                    self.contact_ids.len() - 1
                }
            };
            if let (Some((_, last)), Some(entry)) = (
                self.contact_ids.get_mut(index),
                self.summary.obstacle_contacts.get_mut(index),
            ) {
                if *last != cycle {
                    *last = cycle;
                    entry.cycles += 1;
                }
            }
        }
    }

    /// The segment's figures.
    pub fn finish(mut self) -> SegmentSummary {
        self.summary.torques = self.torques.figures();
        self.summary.crossings = self.crossings.finish();
        let start_s = self.summary.start_s;
        let track = std::mem::take(&mut self.track).into_vec();
        if let Some(&(_, x1, y1, _)) = track.iter().find(|(t, ..)| *t >= start_s + 1.0) {
            self.summary.moved_after_1s_m = track
                .iter()
                .filter(|(t, ..)| *t >= start_s + 1.0)
                .map(|(_, x, y, _)| (x - x1).hypot(y - y1))
                .fold(0.0, f64::max);
        }
        if let Some(&(end_s, x, y, yaw)) = track.last() {
            let left = track.iter().rev().find(|(_, tx, ty, tyaw)| {
                (tx - x).hypot(ty - y) > STOPPED_RADIUS_M || (tyaw - yaw).abs() > STOPPED_YAW_DEG
            });
            self.summary.settled_after_s = match left {
                None => Some(0.0),
                Some(&(t, ..)) if end_s - t < 0.1 => None,
                Some(&(t, ..)) => Some((t - self.summary.start_s).max(0.0)),
            };
        }
        self.summary
    }
}
