//! All emulated nodes of the robot together — four leg drives, the wheel drive, the IMU, the
//! rangefinder — and the bus schedule they follow ([`protocol::busload::SCHEDULE`]): wheel
//! feedback and IMU every cycle, leg feedback at 250 Hz, rangings at 50 Hz, drive status at
//! 10 Hz.
//!
//! The simulator also listens to the controller's status frames, as any bus observer can, to
//! label its telemetry with the controller's mode.

use protocol::busload::SCHEDULE;
use protocol::{
    decode_frame, AnyMessage, ControllerMode, Drive, EncodeError, Frame, Joints, Key, Leg,
    MessageId,
};

use crate::robot::imu::ImuNode;
use crate::robot::leg_drive::LegDrive;
use crate::robot::physics::Physics;
use crate::robot::plant::Plant;
use crate::robot::rangefinder::RangeNode;
use crate::robot::wheel_drive::WheelDrive;

/// The frames the nodes send in one cycle: at most one per slot of the schedule, held without
/// the heap (the simulation's thread allocates nothing per cycle).
pub type FramesDue = heapless::Vec<Frame, { SCHEDULE.len() }>;

/// The robot's CAN nodes.
#[derive(Debug, Clone)]
pub struct Hardware {
    legs: [LegDrive; 4],
    wheel: WheelDrive,
    imu: ImuNode,
    range: RangeNode,
    control_hz: u32,
    controller_mode: Option<ControllerMode>,
}

impl Hardware {
    /// The nodes, sending on the schedule of a controller running at `control_hz`; each leg
    /// drive enforces its joints' `leg_range_rad`; every node joins the sessions it hears with
    /// `key`.
    pub fn new(control_hz: u32, plant: Plant, leg_range_rad: &Joints<[f64; 2]>, key: Key) -> Self {
        let rating = plant.drives.leg_joint;
        Self {
            legs: Leg::ALL.map(|leg| {
                LegDrive::new(leg, *leg_range_rad.leg(leg), key)
                    .rated(rating)
                    .sensing(&plant.sensing)
            }),
            wheel: WheelDrive::new(key)
                .rated(plant.drives.wheel)
                .sensing(&plant.sensing),
            imu: ImuNode::new(plant.imu, plant.imu_noise, key),
            range: RangeNode::new(plant.rangefinder, key),
            control_hz,
            controller_mode: None,
        }
    }

    /// The leg drives, FL FR BL BR.
    pub fn legs(&self) -> &[LegDrive; 4] {
        &self.legs
    }

    /// The wheel drive.
    pub fn wheel(&self) -> &WheelDrive {
        &self.wheel
    }

    /// The IMU node.
    pub fn imu(&self) -> &ImuNode {
        &self.imu
    }

    /// The rangefinder node.
    pub fn rangefinder(&self) -> &RangeNode {
        &self.range
    }

    /// The controller's mode from its last status frame.
    pub fn controller_mode(&self) -> Option<ControllerMode> {
        self.controller_mode
    }

    /// Frames rejected by all drives together.
    pub fn rejected(&self) -> u64 {
        self.legs
            .iter()
            .map(|leg| u64::from(leg.core().rejected()))
            .sum::<u64>()
            + u64::from(self.wheel.core().rejected())
    }

    /// Commands the drives clamped to their ratings, all drives together (see
    /// [`LegDrive::clamped`], [`WheelDrive::clamped`]).
    pub fn clamped(&self) -> u64 {
        self.legs.iter().map(LegDrive::clamped).sum::<u64>() + self.wheel.clamped()
    }

    /// Hands a frame from the bus to every node (each filters and checks it itself).
    pub fn on_frame(&mut self, now_us: u64, frame: &Frame) {
        for leg in &mut self.legs {
            leg.on_frame(now_us, frame);
        }
        self.wheel.on_frame(now_us, frame);
        self.imu.on_frame(frame);
        self.range.on_frame(frame);
        if frame.id() == MessageId::ControllerStatus.raw() {
            if let Ok(decoded) = decode_frame(frame.id(), frame.data()) {
                if let AnyMessage::ControllerStatus(status) = decoded.message {
                    self.controller_mode = Some(status.mode);
                }
            }
        }
    }

    /// Sets the simulation's actuators from the drives' state for the next step.
    pub fn apply(&mut self, now_us: u64, physics: &mut Physics) {
        for leg in &mut self.legs {
            leg.apply(now_us, physics);
        }
        self.wheel.apply(now_us, physics);
    }

    /// The torques the wheel drive applied in the last step, N·m.
    pub fn wheel_torque_nm(&self) -> [f64; 2] {
        self.wheel.applied_torque_nm()
    }

    /// Physics steps in which some drive cut a torque to its rating, summed over the drives.
    pub fn saturated_steps(&self) -> u64 {
        self.legs.iter().map(LegDrive::saturated_steps).sum::<u64>() + self.wheel.saturated_steps()
    }

    /// The frames the nodes send in control cycle `cycle`, in priority order.
    pub fn frames_due(
        &mut self,
        now_us: u64,
        cycle: u32,
        physics: &Physics,
    ) -> Result<FramesDue, EncodeError> {
        let mut frames = FramesDue::new();
        self.range.observe(physics);
        for slot in SCHEDULE
            .iter()
            .filter(|s| s.sends_in(cycle, self.control_hz))
        {
            let sealed = match slot.id {
                MessageId::LegFeedback(leg) => {
                    let drive = &mut self.legs[leg as usize];
                    let message = drive.feedback(physics);
                    drive.core_mut().seal(&message)?
                }
                MessageId::WheelFeedback => {
                    let message = self.wheel.feedback(physics);
                    self.wheel.core_mut().seal(&message)?
                }
                MessageId::Imu => {
                    let message = self.imu.sample(now_us, physics);
                    self.imu.seal(&message)?
                }
                MessageId::Range => {
                    let message = self.range.ranging(physics);
                    self.range.seal(&message)?
                }
                MessageId::DriveStatus(drive) => {
                    let core = match drive {
                        Drive::Wheel => self.wheel.core_mut(),
                        leg => self.legs[leg as usize].core_mut(),
                    };
                    let message = AnyMessage::DriveStatus(drive, core.status(now_us));
                    core.seal(&message)?
                }
                _ => continue,
            };
            // A node that has not heard the controller's announcement yet sends nothing. The
            // schedule has a slot per frame, so there is always room.
            if let Some(frame) = sealed {
                let pushed = frames.push(frame);
                debug_assert!(pushed.is_ok(), "a slot of the schedule per frame");
            }
        }
        Ok(frames)
    }
}
