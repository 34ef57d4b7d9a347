//! The emulated drives enforce their own ratings whatever the wire says: an authentic command
//! beyond them is clamped, applied within them, and counted.

use protocol::SessionTime;
use protocol::{
    Angle, Announce, AnyMessage, DriveEnable, Epoch, Frame, Joints, Leg, LegTargets, Session,
    Torque, WheelCommand, WireVersion, TEST_KEY,
};
use sim_host::robot::leg_drive::LegDrive;
use sim_host::robot::wheel_drive::{WheelDrive, WHEEL_PEAK_TORQUE_NM};

/// The controller's session, which the drives join on its announcement.
const SESSION: Session = Session::owned(TEST_KEY, Epoch::new(1));

fn announce() -> Frame {
    AnyMessage::Announce(Announce {
        version: WireVersion::THIS,
        epoch: Epoch::new(1),
        time: SessionTime::from_ms(0),
    })
    .encode(&SESSION, 0)
    .unwrap()
}

#[test]
fn a_wheel_command_above_the_rating_is_applied_at_the_rating_and_counted() {
    let mut drive = WheelDrive::new(TEST_KEY);
    drive.on_frame(0, &announce());
    let command = |torque_nm: [f32; 2], counter: u32| {
        AnyMessage::WheelCommand(WheelCommand {
            enable: DriveEnable::Enabled,
            torque: torque_nm.map(Torque::saturating_from_si),
        })
        .encode(&SESSION, counter)
        .unwrap()
    };
    drive.on_frame(0, &command([300.0, -300.0], 0));
    assert_eq!(
        drive.commanded_torque_nm(),
        [WHEEL_PEAK_TORQUE_NM, -WHEEL_PEAK_TORQUE_NM]
    );
    assert_eq!(drive.clamped(), 1);
    drive.on_frame(4_000, &command([12.5, -3.0], 1));
    assert_eq!(drive.commanded_torque_nm(), [12.5, -3.0]);
    assert_eq!(
        drive.clamped(),
        1,
        "a command within the rating is not counted"
    );
}

#[test]
fn leg_targets_outside_the_joint_range_are_held_at_the_range_and_counted() {
    let deg = |d: f64| d.to_radians();
    // The model's ranges: hip abduction ±35°, hip pitch ±50°, knee −110…15°, ankle ±40°.
    let range = [
        [deg(-35.0), deg(35.0)],
        [deg(-50.0), deg(50.0)],
        [deg(-110.0), deg(15.0)],
        [deg(-40.0), deg(40.0)],
    ];
    let mut drive = LegDrive::new(Leg::Fl, range, TEST_KEY);
    drive.on_frame(0, &announce());
    let targets = |fl_deg: [f64; 4], counter: u32| {
        let mut position = Joints::splat(Angle::saturating_from_si(0.0));
        for (slot, d) in position.leg_mut(Leg::Fl).iter_mut().zip(fl_deg) {
            *slot = Angle::saturating_from_si(deg(d) as f32);
        }
        AnyMessage::LegTargets(LegTargets {
            enable: DriveEnable::Enabled,
            position,
        })
        .encode(&SESSION, counter)
        .unwrap()
    };
    drive.on_frame(0, &targets([0.0, 80.0, 60.0, -90.0], 0));
    let held = drive.targets_rad().map(f64::to_degrees);
    let expected = [0.0, 50.0, 15.0, -40.0];
    for (joint, (held, expected)) in held.iter().zip(expected).enumerate() {
        assert!(
            (held - expected).abs() < 0.01,
            "joint {joint}: {held}° for {expected}°"
        );
    }
    assert_eq!(drive.clamped(), 1);
    // Exactly on the limits, as the controller's fold puts the hip: not clamped.
    drive.on_frame(4_000, &targets([35.0, 50.0, -110.0, 40.0], 1));
    assert_eq!(drive.clamped(), 1);
}
