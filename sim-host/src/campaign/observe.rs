//! One run of a scenario on one plant: the closed loop of [`crate::faults::rig`] (the real
//! firmware on the in-process bus, lockstep) and what a judge needs from it — the segments'
//! figures from ground truth, the first fall, the first abort the firmware reported, and for
//! the E-stop scenario the stop's figures.

use std::path::Path;
use std::sync::Mutex;

use firmware::control::fsm::{State, WheelMotion};
use host_can::fault_plan::Faults;
use protocol::{AnyMessage, EStop, FaultFlags, NodeId, Session, TEST_KEY};

use crate::campaign::estop::StopTracker;
use crate::campaign::scenario::Scenario;
use crate::faults::rig::{Rig, PERIOD_US};
use crate::output::metrics::{BusCounters, SegmentSummary, SegmentTracker, JOINT_TOLERANCE_RAD};
use crate::robot::plant::Plant;
use crate::session::SessionError;

pub use crate::campaign::estop::StopFigures;

/// The firmware stopping the robot on its own and saying why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Abort {
    /// Rig time, s.
    pub at_s: f64,
    /// The flags it reported then.
    pub flags: FaultFlags,
}

/// What a run showed.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Per segment of [`Scenario::segments`], its figures.
    pub segments: Vec<SegmentSummary>,
    /// First cycle fallen (tilt past 45° or the torso down), rig time, s.
    pub fell_at_s: Option<f64>,
    /// First cycle in `Fault`, or in `EStop` before any E-stop was sent, with a cause flag, or
    /// refusing motion on a degraded link (`link_degraded` reported).
    pub abort: Option<Abort>,
    /// First cycle balancing on the wheels, rig time, s.
    pub balancing_at_s: Option<f64>,
    /// The firmware's state at the end.
    pub final_state: Option<State>,
    /// The E-stop's figures (the E-stop scenario only).
    pub stop: Option<StopFigures>,
    /// Cycles whose command came late (transport delay shows here).
    pub missed_cycles: u64,
    /// The cause flags the firmware showed on the last cycle: a miss it did not stop for but
    /// said why. Left out: the start-up interlock's `awaiting_stop`, and `estop_latched`, which
    /// tells of an E-stop, not why a figure was missed (one nobody sent is an abort).
    pub reported: FaultFlags,
    /// Leg joints past their ranges while the legs were powered (a torque-free leg resting on
    /// its mechanical stop after an E-stop is not the controller's doing).
    pub joint_limits: JointExcess,
    /// … and while every leg drive was torque-free (reported, not judged).
    pub joint_limits_torque_free: JointExcess,
}

/// Cycles with a leg joint past its range by more than
/// [`crate::output::metrics::JOINT_TOLERANCE_RAD`], and the largest excess.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointExcess {
    /// Cycles past the tolerance.
    pub cycles: u64,
    /// Largest excess, degrees.
    pub max_deg: f64,
    /// The first cycle past the tolerance, rig time, s.
    pub first_at_s: Option<f64>,
}

impl JointExcess {
    /// Takes one cycle's largest excess, rad (≤ 0 inside the range).
    fn observe(&mut self, excess_rad: f64, t: f64) {
        self.max_deg = self.max_deg.max(excess_rad.max(0.0).to_degrees());
        if excess_rad > JOINT_TOLERANCE_RAD {
            self.cycles += 1;
            self.first_at_s.get_or_insert(t);
        }
    }
}

/// The largest distance of any leg joint past its range now, rad (negative inside).
fn joint_excess_rad(rig: &Rig) -> f64 {
    let ranges = firmware::config::Config::ROBOT.limits.ranges;
    let mut excess = f64::NEG_INFINITY;
    for (_, angles) in rig.sim().physics().leg_positions_rad().iter_legs() {
        for (angle, range) in angles.iter().zip(ranges) {
            let (lo, hi) = (f64::from(range.min_rad), f64::from(range.max_rad));
            excess = excess.max(lo - angle).max(angle - hi);
        }
    }
    excess
}

/// MuJoCo's XML loader keeps global state in some versions: models are loaded one at a time
/// (a few milliseconds each), the runs themselves in parallel.
static LOADING: Mutex<()> = Mutex::new(());

/// Runs `scenario` on `plant` with `faults` on the simulator's connection.
pub fn run(
    model: &Path,
    scenario: Scenario,
    plant: Plant,
    faults: &Faults,
) -> Result<Observation, SessionError> {
    let mut rig = {
        let _loading = LOADING
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        Rig::with_plant(model, scenario.plan(), faults, &Faults::default(), plant)?
    };
    let mut watch = Watch::new(scenario, &rig);
    let end_us = (scenario.duration_s() * 1e6).round() as u64;
    let latch_us = scenario.estop_at_s().map(|s| (s * 1e6).round() as u64);
    while rig.stats().cycles * PERIOD_US < end_us {
        let now_us = rig.stats().cycles * PERIOD_US;
        if latch_us == Some(now_us) {
            watch.stop = Some(StopTracker::start(&rig));
            rig.tool_send(&latch_frame()?)?;
        }
        rig.step()?;
        watch.observe(&rig);
    }
    Ok(watch.finish(&rig))
}

/// The E-stop panel's constant latch frame (bound to no session).
fn latch_frame() -> Result<protocol::Frame, SessionError> {
    AnyMessage::EStop(EStop::latch(NodeId::Tool))
        .encode(&Session::unjoined(TEST_KEY), 0)
        .map_err(|_| SessionError::Internal("the E-stop latch frame"))
}

/// The run as it goes.
struct Watch {
    scenario: Scenario,
    current: SegmentTracker,
    next_segment: usize,
    done: Vec<SegmentSummary>,
    fell_at_s: Option<f64>,
    abort: Option<Abort>,
    balancing_at_s: Option<f64>,
    stop: Option<StopTracker>,
    joint_limits: JointExcess,
    joint_limits_torque_free: JointExcess,
}

impl Watch {
    fn new(scenario: Scenario, rig: &Rig) -> Self {
        let (_, label) = scenario.segments()[0];
        Self {
            scenario,
            current: SegmentTracker::start(label, label, rig.sim(), BusCounters::default(), &[]),
            next_segment: 1,
            done: Vec::new(),
            fell_at_s: None,
            abort: None,
            balancing_at_s: None,
            stop: None,
            joint_limits: JointExcess::default(),
            joint_limits_torque_free: JointExcess::default(),
        }
    }

    /// Takes the cycle `rig` just ran.
    fn observe(&mut self, rig: &Rig) {
        let Some(record) = rig.records().last() else {
            return;
        };
        let t = rig.time_s();
        if let Some(&(start_s, label)) = self.scenario.segments().get(self.next_segment) {
            // Segments change on the cycle that starts at or after their start.
            if t - PERIOD_US as f64 * 1e-6 >= start_s - 1e-9 {
                let next =
                    SegmentTracker::start(label, label, rig.sim(), BusCounters::default(), &[]);
                self.done
                    .push(std::mem::replace(&mut self.current, next).finish());
                self.next_segment += 1;
            }
        }
        self.current.observe(rig.sim(), BusCounters::default());
        if record.fallen() && self.fell_at_s.is_none() {
            self.fell_at_s = Some(t);
        }
        let estop_sent = self.stop.is_some();
        // A degraded link and a blocked trot are the controller's stops outside `Fault`: it
        // stops once and reports the flag (on flat ground a blocked trot is a false stop, and
        // its verdict says so with the cause).
        let stopped = match record.state {
            Some(State::Fault) => true,
            Some(State::EStop) => !estop_sent,
            _ => {
                record.faults.contains(FaultFlags::LINK_DEGRADED)
                    || record.faults.contains(FaultFlags::LEG_BLOCKED)
            }
        };
        let cause = record.faults.without(FaultFlags::AWAITING_STOP);
        if stopped && self.abort.is_none() && !cause.is_empty() {
            self.abort = Some(Abort {
                at_s: t,
                flags: record.faults,
            });
        }
        if matches!(record.state, Some(State::Wheels(WheelMotion::Balance)))
            && self.balancing_at_s.is_none()
        {
            self.balancing_at_s = Some(t);
        }
        if let Some(stop) = &mut self.stop {
            stop.observe(rig, record);
        }
        let legs_powered = record.torque_off.iter().take(4).any(|off| !off);
        let excess = joint_excess_rad(rig);
        if legs_powered {
            self.joint_limits.observe(excess, t);
        } else {
            self.joint_limits_torque_free.observe(excess, t);
        }
    }

    fn finish(mut self, rig: &Rig) -> Observation {
        self.done.push(self.current.finish());
        Observation {
            segments: self.done,
            fell_at_s: self.fell_at_s,
            abort: self.abort,
            balancing_at_s: self.balancing_at_s,
            final_state: rig.records().last().and_then(|r| r.state),
            stop: self.stop.map(StopTracker::finish),
            missed_cycles: rig.stats().missed_cycles,
            reported: rig.records().last().map_or(FaultFlags::EMPTY, |r| {
                r.faults
                    .without(FaultFlags::AWAITING_STOP)
                    .without(FaultFlags::ESTOP_LATCHED)
            }),
            joint_limits: self.joint_limits,
            joint_limits_torque_free: self.joint_limits_torque_free,
        }
    }
}
