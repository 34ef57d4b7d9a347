//! Strategies producing every message with arbitrary in-range values.
#![allow(dead_code)]

use proptest::prelude::*;
use protocol::*;

macro_rules! raw_strategy {
    ($fn:ident, $ty:ident, $raw:ty) => {
        pub fn $fn() -> impl Strategy<Value = $ty> {
            (<$raw>::from($ty::RAW_MIN)..=<$raw>::from($ty::RAW_MAX))
                .prop_map(|r| $ty::from_raw(r).unwrap())
        }
    };
}
raw_strategy!(angle, Angle, i16);
raw_strategy!(wheel_angle, WheelAngle, i16);
raw_strategy!(joint_velocity, JointVelocity, i16);
raw_strategy!(wheel_velocity, WheelVelocity, i16);
raw_strategy!(torque, Torque, i16);
raw_strategy!(quat, QuatComponent, i16);
raw_strategy!(rate, AngularRate, i16);
raw_strategy!(accel, Acceleration, i16);
raw_strategy!(height, BodyHeight, i16);
raw_strategy!(speed, SpeedScale, u8);
raw_strategy!(tick, Tick, u32);
raw_strategy!(millis, Millis, u32);
raw_strategy!(count, Count, u16);

fn pick<T: Copy + core::fmt::Debug + 'static>(all: &'static [T]) -> impl Strategy<Value = T> {
    proptest::sample::select(all)
}

pub fn any_message() -> impl Strategy<Value = AnyMessage> {
    prop_oneof![
        (pick(EStopAction::ALL), pick(&NodeId::ALL))
            .prop_map(|(action, source)| AnyMessage::EStop(EStop { action, source })),
        tick().prop_map(|tick| AnyMessage::Sync(Sync { tick })),
        (pick(DriveEnable::ALL), proptest::array::uniform16(angle())).prop_map(
            |(enable, position)| AnyMessage::LegTargets(LegTargets {
                enable,
                position: position.into()
            })
        ),
        proptest::array::uniform2(torque())
            .prop_map(|torque| AnyMessage::WheelCommand(WheelCommand { torque })),
        (
            pick(&Leg::ALL),
            proptest::array::uniform4(angle()),
            proptest::array::uniform4(joint_velocity()),
            proptest::array::uniform4(torque())
        )
            .prop_map(|(leg, position, velocity, effort)| AnyMessage::LegFeedback(
                leg,
                LegFeedback {
                    position,
                    velocity,
                    effort
                }
            )),
        (
            proptest::array::uniform2(wheel_angle()),
            proptest::array::uniform2(wheel_velocity()),
            proptest::array::uniform2(torque())
        )
            .prop_map(|(position, velocity, effort)| AnyMessage::WheelFeedback(
                WheelFeedback {
                    position,
                    velocity,
                    effort
                }
            )),
        (
            proptest::array::uniform4(quat()),
            proptest::array::uniform3(rate()),
            proptest::array::uniform3(accel())
        )
            .prop_map(
                |(orientation, angular_rate, acceleration)| AnyMessage::Imu(Imu {
                    orientation,
                    angular_rate,
                    acceleration
                })
            ),
        (pick(TeleopMode::ALL), height(), speed()).prop_map(|(mode, body_height, speed_scale)| {
            AnyMessage::TeleopCommand(TeleopCommand {
                mode,
                body_height,
                speed_scale,
            })
        }),
        millis().prop_map(|uptime| AnyMessage::TeleopHeartbeat(TeleopHeartbeat { uptime })),
        (
            pick(ControllerMode::ALL),
            0..=FaultFlags::KNOWN,
            tick(),
            height(),
            angle(),
            angle()
        )
            .prop_map(|(mode, faults, tick, body_height, pitch, roll)| {
                AnyMessage::ControllerStatus(ControllerStatus {
                    mode,
                    faults: FaultFlags::from_bits(faults).unwrap(),
                    tick,
                    body_height,
                    pitch,
                    roll,
                })
            }),
        (pick(&Drive::ALL), 0..=DriveFlags::KNOWN, count(), count()).prop_map(
            |(drive, flags, rejected, commands)| {
                AnyMessage::DriveStatus(
                    drive,
                    DriveStatus {
                        flags: DriveFlags::from_bits(flags).unwrap(),
                        rejected,
                        commands,
                    },
                )
            }
        ),
        (proptest::array::uniform7(count()), count()).prop_map(|(rejected, lost)| {
            AnyMessage::RejectCounters(RejectCounters { rejected, lost })
        }),
    ]
}
