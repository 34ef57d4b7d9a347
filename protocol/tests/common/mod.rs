//! Strategies producing every message with arbitrary in-range values.
#![allow(dead_code)]

use proptest::prelude::*;
use protocol::*;

pub mod bus;
pub mod checker;
pub mod clock;
pub mod frames;
pub mod protected;
pub mod recorded;
pub mod rejects;
pub mod search;

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
raw_strategy!(rate, AngularRate, i16);
raw_strategy!(accel, Acceleration, i16);
raw_strategy!(height, BodyHeight, i16);
raw_strategy!(speed, SpeedScale, u8);
raw_strategy!(ground_speed, GroundSpeed, i16);
raw_strategy!(yaw_rate, YawRate, i16);
raw_strategy!(tick, Tick, u32);
raw_strategy!(millis, Millis, u32);
raw_strategy!(count, Count, u16);
raw_strategy!(token, ReleaseToken, u16);
raw_strategy!(epoch, Epoch, u32);
raw_strategy!(version, WireVersion, u8);

fn pick<T: Copy + core::fmt::Debug + 'static>(all: &'static [T]) -> impl Strategy<Value = T> {
    proptest::sample::select(all)
}

pub fn any_message() -> impl Strategy<Value = AnyMessage> {
    prop_oneof![
        (pick(EStopAction::ALL), pick(&NodeId::ALL), token()).prop_map(
            |(action, source, token)| AnyMessage::EStop(EStop {
                action,
                source,
                token
            })
        ),
        tick().prop_map(|tick| AnyMessage::Sync(Sync { tick })),
        (version(), epoch(), any::<u32>()).prop_map(|(version, epoch, ms)| {
            AnyMessage::Announce(Announce {
                version,
                epoch,
                time: SessionTime::from_ms(ms),
            })
        }),
        (pick(DriveEnable::ALL), proptest::array::uniform16(angle())).prop_map(
            |(enable, position)| AnyMessage::LegTargets(LegTargets {
                enable,
                position: position.into()
            })
        ),
        (pick(DriveEnable::ALL), proptest::array::uniform2(torque()))
            .prop_map(|(enable, torque)| AnyMessage::WheelCommand(WheelCommand { enable, torque })),
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
            proptest::array::uniform2(wheel_velocity()),
            proptest::array::uniform2(torque())
        )
            .prop_map(
                |(velocity, effort)| AnyMessage::WheelFeedback(WheelFeedback { velocity, effort })
            ),
        (
            proptest::array::uniform3(rate()),
            proptest::array::uniform3(accel())
        )
            .prop_map(|(angular_rate, acceleration)| AnyMessage::Imu(Imu {
                angular_rate,
                acceleration
            })),
        (0_u16..=4_000, pick(RangeStatus::ALL)).prop_map(|(mm, status)| {
            AnyMessage::Range(Range {
                distance: RangeDistance::from_raw(mm).unwrap(),
                status,
            })
        }),
        (
            pick(TeleopMode::ALL),
            height(),
            speed(),
            ground_speed(),
            yaw_rate()
        )
            .prop_map(|(mode, body_height, speed_scale, speed, yaw_rate)| {
                AnyMessage::TeleopCommand(TeleopCommand {
                    mode,
                    body_height,
                    speed_scale,
                    speed,
                    yaw_rate,
                })
            }),
        millis().prop_map(|uptime| AnyMessage::TeleopHeartbeat(TeleopHeartbeat { uptime })),
        (
            pick(ControllerMode::ALL),
            0..=FaultFlags::KNOWN,
            tick(),
            height(),
            angle(),
            angle(),
            token()
        )
            .prop_map(
                |(mode, faults, tick, body_height, pitch, roll, release_token)| {
                    AnyMessage::ControllerStatus(ControllerStatus {
                        mode,
                        faults: FaultFlags::from_bits(faults).unwrap(),
                        tick,
                        body_height,
                        pitch,
                        roll,
                        release_token,
                    })
                }
            ),
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
        (proptest::array::uniform10(count()), count()).prop_map(|(rejected, lost)| {
            AnyMessage::RejectCounters(RejectCounters { rejected, lost })
        }),
    ]
}

/// The epoch of the tests' controller.
pub const EPOCH: Epoch = Epoch::new(41);

/// The session the tests' controller owns.
pub fn controller_session() -> Session {
    Session::owned(TEST_KEY, EPOCH)
}

/// The controller's announcement of `epoch` in version `version` at session time `counter`
/// × 100 ms, sealed with announcement counter `counter`.
pub fn announce_frame(version: WireVersion, epoch: Epoch, counter: u32) -> Frame {
    announce_frame_at(version, epoch, counter.saturating_mul(100), counter)
}

/// The controller's announcement of `epoch` in version `version` at session time `ms`, sealed
/// with announcement counter `counter`.
pub fn announce_frame_at(version: WireVersion, epoch: Epoch, ms: u32, counter: u32) -> Frame {
    let time = SessionTime::from_ms(ms);
    AnyMessage::Announce(Announce {
        version,
        epoch,
        time,
    })
    .encode(&Session::owned(TEST_KEY, epoch).at(time), counter)
    .unwrap()
}

/// A member receiver that heard the announcement of `epoch` (counter 0, session time 0) and
/// joined.
pub fn joined_member(epoch: Epoch) -> Receiver {
    member_at(epoch, 0)
}

/// A member receiver that joined on the announcement of `epoch` at session time `ms`.
pub fn member_at(epoch: Epoch, ms: u32) -> Receiver {
    let mut member = Receiver::member(TEST_KEY);
    let frame = announce_frame_at(WireVersion::THIS, epoch, ms, ms / 100);
    member.receive(frame.id(), frame.data()).unwrap();
    assert_eq!(member.session().epoch(), Some(epoch));
    assert_eq!(member.session().time(), SessionTime::from_ms(ms));
    member
}

/// The controller's receiver at session time `ms`.
pub fn owner_at(epoch: Epoch, ms: u32) -> Receiver {
    let mut owner = Receiver::owner(Session::owned(TEST_KEY, epoch));
    owner.set_time(SessionTime::from_ms(ms));
    owner
}
