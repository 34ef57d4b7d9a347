//! The bus is readable without this crate: frames produced by the Rust encoder, written as a
//! `candump -L` log, are decoded by Python `cantools` with the generated DBC, and every signal
//! must match the message's value within one quantization step.
//!
//! Needs the project's venv (`cargo xtask setup`), or `PROTOCOL_PYTHON` pointing at a Python
//! with cantools.

mod common;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Command;

use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};
use protocol::*;

/// The physical value of every signal, written out by hand from the message structs — an
/// independent statement of the layout that the DBC must agree with.
fn expected_signals(message: &AnyMessage) -> Vec<(String, f64, f64)> {
    let mut out = Vec::new();
    let mut put = |name: String, value: f64, step: f32| out.push((name, value, f64::from(step)));
    match message {
        AnyMessage::EStop(m) => {
            put("action".into(), f64::from(m.action.raw()), 1.0);
            put("source".into(), f64::from(m.source as u8), 1.0);
            put("token".into(), f64::from(m.token.raw()), 1.0);
        }
        AnyMessage::Sync(m) => put("tick".into(), f64::from(m.tick.raw()), 1.0),
        AnyMessage::Announce(m) => {
            put("version".into(), f64::from(m.version.raw()), 1.0);
            put("epoch".into(), f64::from(m.epoch.raw()), 1.0);
            // In f64: an f32 of seconds loses the millisecond past 2^24 ms.
            put(
                "time".into(),
                f64::from(m.time.ms()) * 1e-3,
                SessionTime::STEP,
            );
        }
        AnyMessage::LegTargets(m) => {
            put("enable".into(), f64::from(m.enable.raw()), 1.0);
            for (name, a) in JOINT_NAMES.iter().zip(m.position) {
                put(format!("position_{name}"), f64::from(a.si()), Angle::STEP);
            }
        }
        AnyMessage::WheelCommand(m) => {
            put("enable".into(), f64::from(m.enable.raw()), 1.0);
            for (name, t) in WHEEL_NAMES.iter().zip(m.torque) {
                put(format!("torque_{name}"), f64::from(t.si()), Torque::STEP);
            }
        }
        AnyMessage::LegFeedback(_, m) => {
            for (i, name) in LEG_JOINT_NAMES.iter().enumerate() {
                put(
                    format!("position_{name}"),
                    f64::from(m.position[i].si()),
                    Angle::STEP,
                );
                put(
                    format!("velocity_{name}"),
                    f64::from(m.velocity[i].si()),
                    JointVelocity::STEP,
                );
                put(
                    format!("effort_{name}"),
                    f64::from(m.effort[i].si()),
                    Torque::STEP,
                );
            }
        }
        AnyMessage::WheelFeedback(m) => {
            for (i, name) in WHEEL_NAMES.iter().enumerate() {
                put(
                    format!("velocity_{name}"),
                    f64::from(m.velocity[i].si()),
                    WheelVelocity::STEP,
                );
                put(
                    format!("effort_{name}"),
                    f64::from(m.effort[i].si()),
                    Torque::STEP,
                );
            }
        }
        AnyMessage::Imu(m) => {
            for (i, axis) in ["x", "y", "z"].iter().enumerate() {
                put(
                    format!("angular_rate_{axis}"),
                    f64::from(m.angular_rate[i].si()),
                    AngularRate::STEP,
                );
                put(
                    format!("acceleration_{axis}"),
                    f64::from(m.acceleration[i].si()),
                    Acceleration::STEP,
                );
            }
        }
        AnyMessage::Range(m) => {
            put(
                "distance".into(),
                f64::from(m.distance.si()),
                RangeDistance::STEP,
            );
            put("status".into(), f64::from(m.status.raw()), 1.0);
        }
        AnyMessage::TeleopCommand(m) => {
            put("mode".into(), f64::from(m.mode.raw()), 1.0);
            put(
                "body_height".into(),
                f64::from(m.body_height.si()),
                BodyHeight::STEP,
            );
            put("speed_scale".into(), f64::from(m.speed_scale.si()), 1.0);
            put("speed".into(), f64::from(m.speed.si()), GroundSpeed::STEP);
            put("yaw_rate".into(), f64::from(m.yaw_rate.si()), YawRate::STEP);
        }
        AnyMessage::TeleopHeartbeat(m) => put("uptime".into(), f64::from(m.uptime.raw()), 1.0),
        AnyMessage::ControllerStatus(m) => {
            put("mode".into(), f64::from(m.mode.raw()), 1.0);
            let flags = [
                "estop_latched",
                "feedback_timeout",
                "imu_timeout",
                "teleop_timeout",
                "tilt_limit",
                "drive_fault",
                "sync_lost",
                "non_finite",
                "link_degraded",
                "awaiting_stop",
                "wheel_stall",
                "runaway",
                "leg_blocked",
                "step_refused",
                "range_timeout",
                "stand_tilted",
            ];
            for (bit, flag) in flags.iter().enumerate() {
                put(
                    format!("faults_{flag}"),
                    f64::from((m.faults.bits() >> bit) & 1),
                    1.0,
                );
            }
            put("tick".into(), f64::from(m.tick.raw()), 1.0);
            put(
                "body_height".into(),
                f64::from(m.body_height.si()),
                BodyHeight::STEP,
            );
            put("pitch".into(), f64::from(m.pitch.si()), Angle::STEP);
            put("roll".into(), f64::from(m.roll.si()), Angle::STEP);
            put(
                "release_token".into(),
                f64::from(m.release_token.raw()),
                1.0,
            );
        }
        AnyMessage::DriveStatus(_, m) => {
            for (bit, flag) in ["enabled", "timed_out", "fault", "estop", "saturated"]
                .iter()
                .enumerate()
            {
                put(
                    format!("flags_{flag}"),
                    f64::from((m.flags.bits() >> bit) & 1),
                    1.0,
                );
            }
            put("rejected".into(), f64::from(m.rejected.raw()), 1.0);
            put("commands".into(), f64::from(m.commands.raw()), 1.0);
        }
        AnyMessage::RejectCounters(m) => {
            for cause in RejectCause::ALL {
                put(
                    format!("rejected_{}", cause.name()),
                    f64::from(m.get(cause).raw()),
                    1.0,
                );
            }
            put("lost".into(), f64::from(m.lost.raw()), 1.0);
        }
    }
    out
}

fn python() -> PathBuf {
    let python = std::env::var_os("PROTOCOL_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../.venv/bin/python"));
    assert!(
        python.exists(),
        "no Python with cantools at {}: run `cargo xtask setup` (or set PROTOCOL_PYTHON)",
        python.display()
    );
    python
}

#[test]
fn cantools_decodes_every_frame_the_rust_encoder_produces() {
    // A fixed seed: the same 400 messages every run, covering every identifier.
    let mut runner = TestRunner::new_with_rng(
        Config::default(),
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]),
    );
    let strategy = common::any_message();
    let mut messages: Vec<AnyMessage> = (0..400)
        .map(|_| strategy.new_tree(&mut runner).unwrap().current())
        .collect();
    for id in MessageId::ALL {
        assert!(
            messages.iter().any(|m| m.id() == id),
            "sample misses {id:?}"
        );
    }
    messages.sort_by_key(|m| m.id().raw());

    let session = Session::owned(TEST_KEY, Epoch::new(3));
    let mut log = String::new();
    let mut checks = Vec::new();
    for (i, message) in messages.iter().enumerate() {
        let frame = message.encode(&session, i as u32).unwrap();
        checks.push(u32::from_le_bytes(frame.data()[..4].try_into().unwrap()));
        let hex: String = frame.data().iter().map(|b| format!("{b:02X}")).collect();
        log.push_str(&format!(
            "({}.{:06}) vcan0 {:03X}##1{hex}\n",
            i / 1000,
            i % 1000,
            frame.id()
        ));
    }
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let log_path = dir.join("cantools_frames.log");
    std::fs::write(&log_path, log).unwrap();

    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let output = Command::new(python())
        .arg(manifest.join("tests/cantools_decode.py"))
        .arg(manifest.join("hybrid_robot.dbc"))
        .arg(&log_path)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "cantools failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let decoded: Vec<serde_json::Value> = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(decoded.len(), messages.len());

    for (i, (message, py)) in messages.iter().zip(&decoded).enumerate() {
        assert_eq!(py["id"], u64::from(message.id().raw()));
        assert_eq!(py["name"], message.id().layout().name);
        let signals: BTreeMap<String, f64> = py["signals"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| (k.clone(), v.as_f64().unwrap()))
            .collect();
        assert_eq!(signals["E2E_Counter"], i as f64);
        assert_eq!(signals["E2E_Check"], f64::from(checks[i]));
        let expected = expected_signals(message);
        assert_eq!(
            signals.len(),
            expected.len() + 2,
            "{}: signal count",
            py["name"]
        );
        for (name, value, step) in expected {
            let got = signals
                .get(&name)
                .unwrap_or_else(|| panic!("{}: no signal {name}", py["name"]));
            assert!(
                (got - value).abs() <= step,
                "{} {name}: cantools {got}, Rust {value} (step {step})",
                py["name"]
            );
        }
    }
}
