//! The controlled stop: the E-stop's latch, and the stall or runaway that stops the robot
//! into `Fault` the same way (see [`crate::control::stop`]).

use protocol::FaultFlags;

use super::Controller;
use crate::control::fsm::{Event, State};
use crate::control::stop::{Carrier, Stop, StopCommand, StopInput};
use crate::legs::crawl::legs_load_n;
use crate::time::Tick;

impl Controller {
    /// An E-stop latch at `now`: `EStop` from this tick on, with a controlled stop if the robot
    /// is under way, or every drive torque-free at once from `Hold`, `Fault` or unarmed (see
    /// [`crate::control::stop`]). A latch while latched changes nothing.
    pub(super) fn latch(&mut self, now: Tick) {
        if self.state == State::EStop {
            // A new latch outranks a release still waiting for the stop to end.
            self.release_pending = false;
            return;
        }
        if self.state == State::Fault && self.stop.is_some_and(|stop| !stop.off()) {
            // A stall or runaway is already being stopped under control: the latch keeps it.
            self.apply(Event::EStopLatch);
            return;
        }
        let carrier = if !self.armed || matches!(self.state, State::Hold | State::Fault) {
            Carrier::Nothing
        } else if self.wheels_may_drive() {
            Carrier::Wheels
        } else {
            Carrier::Legs
        };
        self.start_stop(now, carrier);
        self.apply(Event::EStopLatch);
    }

    /// Starts the controlled stop at `now` for what carries the robot.
    fn start_stop(&mut self, now: Tick, carrier: Carrier) {
        let (config, rate) = (self.config.stop, self.config.rate);
        let fold_rad = self.stop_fold_rad();
        self.stop = Some(Stop::new(
            config,
            rate,
            now,
            self.legs_rad,
            fold_rad,
            carrier,
        ));
    }

    /// An authentic release (the node has checked its token): `Hold` — or `Fault` while a drive
    /// fault or a frozen SYNC remains — once the controlled stop is over. A release heard while
    /// the stop still brakes or sets the robot down waits for its end: in `Hold` nothing
    /// balances, and a robot released mid-brake tipped 19° over.
    pub(super) fn release(&mut self) {
        if self.state != State::EStop {
            return;
        }
        if !self.stop.is_none_or(|stop| stop.cut()) {
            self.release_pending = true;
            return;
        }
        self.apply(Event::EStopClear);
        self.fault_on_held_cause();
    }

    /// Takes a waiting release once the stop is over (call after [`Controller::run_stop`]:
    /// the tick the stop ends is torque-free, as a stop of category 1 ends, before anything is
    /// re-enabled).
    pub(super) fn release_when_stopped(&mut self) {
        if self.release_pending && self.stop.is_none_or(|stop| stop.cut()) {
            self.release();
        }
    }

    /// Runs this tick of the controlled stop: whether the legs stay enabled.
    pub(super) fn run_stop(&mut self, now: Tick) -> bool {
        match self.stop_command(now) {
            StopCommand::Servo(targets) => {
                self.legs_rad = targets;
                true
            }
            StopCommand::Off => {
                self.follow_measured();
                false
            }
        }
    }

    /// A stall or runaway (`cause`) found at `now` on the wheels: `Fault`, with the controlled
    /// stop of an E-stop on the wheels (brake from the present speed, kickstand, torque off),
    /// since the controller itself is sound and cutting the torque would drop the robot.
    pub(super) fn wheel_fault_stop(&mut self, now: Tick, cause: FaultFlags, ground_speed_m_s: f32) {
        self.apply(Event::Fault);
        if self.state != State::Fault {
            return;
        }
        self.wheel_fault = cause;
        self.balance.rebase(ground_speed_m_s);
        let carrier = if cause == FaultFlags::WHEEL_STALL {
            Carrier::Blocked
        } else {
            Carrier::Wheels
        };
        self.start_stop(now, carrier);
    }

    /// The lean watch on this tick of the balance law: a robot that leans on its legs
    /// ([`crate::wheels::lean`]) goes to `Fault` ([`FaultFlags::RUNAWAY`]) with the controlled
    /// stop of a robot against an obstacle, its wheels held still; `true` if it did. Not while
    /// a controlled stop runs: that stop has the wheels, and the watch does not restart it.
    #[inline(never)] // Its frame stays off the control step's deepest path (PIL stack budget).
    pub(super) fn leans_on_its_legs(&mut self, now: Tick) -> bool {
        if self.stop.is_some() {
            self.lean.reset();
            return false;
        }
        let lean_rad = self.sensors.attitude.pitch_rad - self.balance.pitch_trim_rad();
        let sensors = &self.sensors;
        let geometry = &self.config.geometry;
        // Torques that cannot be read weigh as a load (NaN): the watch does not go blind.
        let legs_load_n = || {
            legs_load_n(
                geometry,
                &sensors.joint_position_rad,
                &sensors.joint_effort_nm,
            )
        };
        if !self.lean.update(&self.config.lean, lean_rad, legs_load_n) {
            return false;
        }
        self.apply(Event::Fault);
        if self.state != State::Fault {
            return false;
        }
        self.wheel_fault = FaultFlags::RUNAWAY;
        // The stop holds the wheels from this tick: no speed to brake from.
        self.start_stop(now, Carrier::Blocked);
        true
    }

    /// This tick of the controlled stop (torque-free if none runs).
    fn stop_command(&mut self, now: Tick) -> StopCommand {
        let r = self.config.balance.wheel_radius_m;
        let input = StopInput {
            now,
            speeds_m_s: [
                self.ground_speed_m_s(),
                r * self.sensors.differential_wheel_rate_rad_s(),
            ],
            braked: self.balance.velocity_ref_m_s() == 0.0,
            fault: self.non_finite || !self.fault_causes(now).is_empty(),
        };
        self.stop
            .as_mut()
            .map_or(StopCommand::Off, |stop| stop.step(&input))
    }
}
