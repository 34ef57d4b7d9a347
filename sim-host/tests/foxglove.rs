//! The run as Foxglove opens it (`output::foxglove`): the MCAP read back by the official Python
//! reader (the project venv's `mcap`, not this crate's writer), its transforms against the torso
//! pose sampled from MuJoCo as the run went, the URDF through a URDF parser, the transform chain
//! against MuJoCo's own body poses, and the live server through a plain WebSocket client.

mod common;

use std::collections::BTreeMap;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use common::config;
use host_can::fault_plan::Faults;
use protocol::TeleopMode;
use sim_host::faults::rig::Rig;
use sim_host::output::foxglove::bodies::{Pose, RobotTree};
use sim_host::output::foxglove::ROOT_BODY;
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::robot::rotation::rpy_rad;
use sim_host::session;
use teleop_core::scripted::PlanStep;

/// Stand, then a steered trot: every link moves.
fn plan() -> Vec<PlanStep> {
    vec![
        PlanStep::at(0.0, TeleopMode::Stand),
        PlanStep::at(1.0, TeleopMode::TrotForward).with_velocity(0.0, 0.3),
    ]
}

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("foxglove")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn the_mcap_opens_in_an_independent_reader_with_every_channel_and_mujocos_torso_pose() {
    let dir = out_dir("mcap");
    let mut cfg = config(Plant::default(), plan(), Vec::new(), 4.0);
    cfg.out_dir = Some(dir.clone());
    let report = session::run(&cfg).unwrap();
    let read = common::read_mcap(&dir.join("run.mcap"));
    let channels: BTreeMap<String, (String, String, u64)> = read["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["topic"].as_str().unwrap().to_owned(),
                (
                    c["schema"].as_str().unwrap().to_owned(),
                    c["encoding"].as_str().unwrap().to_owned(),
                    c["count"].as_u64().unwrap(),
                ),
            )
        })
        .collect();
    let cycles = report.rows.len() as u64;
    println!("MEASURED MCAP channels over {cycles} cycles: {channels:?}");
    let expect = |topic: &str, schema: &str, encoding: &str| {
        let (s, e, count) = channels
            .get(topic)
            .unwrap_or_else(|| panic!("no channel {topic}: {channels:?}"));
        assert_eq!((s.as_str(), e.as_str()), (schema, encoding), "{topic}");
        *count
    };
    // Transforms at 50 Hz and joint states at 125 Hz, from 250 Hz.
    assert_eq!(
        expect("/tf", "foxglove.FrameTransforms", "protobuf"),
        cycles / 5
    );
    assert_eq!(
        expect("/joint_states", "jointstate.JointState", "protobuf"),
        cycles / 2
    );
    // The IMU and the wheel drive send every cycle, the controller's status at 50 Hz.
    assert_eq!(expect("/imu", "imu.Imu", "protobuf"), cycles);
    assert_eq!(
        expect("/wheels", "wheelfeedback.WheelFeedback", "protobuf"),
        cycles
    );
    let status = expect(
        "/controller/status",
        "controllerstatus.ControllerStatus",
        "protobuf",
    );
    assert!(status.abs_diff(cycles / 5) <= 2, "{status}");
    assert!(expect("/controller/log", "foxglove.Log", "protobuf") >= 3);
    // The bus's frames, a message per cycle.
    let can = expect("/can", "canframes.CanFrames", "protobuf");
    assert!(can.abs_diff(cycles) <= 1, "{can}");
    assert!(expect("/robot_description", "std_msgs/String", "json") >= 4);
    assert_eq!(read["attachments"], serde_json::json!(["robot.urdf"]));
    let names = read["joint_names"].as_array().unwrap();
    assert_eq!(names.len(), 18);
    assert!(names.contains(&serde_json::json!("knee_fl")), "{names:?}");
    // The documented layout shows only topics the log has.
    let layout = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/foxglove/layout.json"),
    )
    .unwrap();
    let layout: serde_json::Value = serde_json::from_str(&layout).unwrap();
    let mut named = Vec::new();
    topics_in(&layout, &mut named);
    assert!(named.len() >= 8, "{named:?}");
    for topic in named {
        assert!(
            channels.contains_key(&topic),
            "the layout shows {topic}, the log has no such topic"
        );
    }

    // Every torso transform is MuJoCo's torso pose of its cycle, as the run sampled it.
    let torso = read["torso"].as_array().unwrap();
    assert_eq!(torso.len() as u64, cycles / 5);
    let rows: BTreeMap<u64, &sim_host::output::telemetry::TelemetryRow> = report
        .rows
        .iter()
        .map(|row| ((row.time_s * 1e9).round() as u64, row))
        .collect();
    let mut worst_m: f64 = 0.0;
    let mut worst_deg: f64 = 0.0;
    for t in torso {
        let row = rows[&t["log_time_ns"].as_u64().unwrap()];
        let xyz: Vec<f64> = serde_json::from_value(t["xyz"].clone()).unwrap();
        let wxyz: [f64; 4] = serde_json::from_value(t["wxyz"].clone()).unwrap();
        for (logged, sampled) in xyz.iter().zip(row.torso_pos_m) {
            worst_m = worst_m.max((logged - sampled).abs());
        }
        for (logged, sampled) in rpy_rad(wxyz)
            .map(f64::to_degrees)
            .iter()
            .zip(row.torso_rpy_deg)
        {
            worst_deg = worst_deg.max((logged - sampled).abs());
        }
    }
    println!("MEASURED torso transform vs MuJoCo: worst {worst_m:e} m, {worst_deg:e} deg");
    assert!(
        worst_m < 1e-3 && worst_deg < 0.01,
        "{worst_m} m, {worst_deg} deg"
    );
}

/// The topics a layout's panels name: the part of every `/…` string value before a field path.
fn topics_in(value: &serde_json::Value, out: &mut Vec<String>) {
    match value {
        serde_json::Value::String(s) if s.starts_with('/') => {
            let end = s.find(['.', '[']).unwrap_or(s.len());
            out.push(s[..end].to_owned());
        }
        serde_json::Value::Array(items) => items.iter().for_each(|v| topics_in(v, out)),
        serde_json::Value::Object(map) => map.values().for_each(|v| topics_in(v, out)),
        _ => {}
    }
}

#[test]
fn the_urdf_parses_and_names_the_models_joints() {
    let dir = out_dir("urdf");
    let mut cfg = config(Plant::default(), plan(), Vec::new(), 0.2);
    cfg.out_dir = Some(dir.clone());
    cfg.plots = false;
    session::run(&cfg).unwrap();
    // A second run into the same folder replaces the logs, as the demo's reruns do.
    let again = session::run(&cfg).unwrap();
    assert!(again.files.contains(&dir.join("run.mcap")));
    let robot = urdf_rs::read_file(dir.join("robot.urdf")).unwrap();
    let mut movable: Vec<String> = robot
        .joints
        .iter()
        .filter(|j| !matches!(j.joint_type, urdf_rs::JointType::Fixed))
        .map(|j| j.name.clone())
        .collect();
    movable.sort();
    // The model's hinge joints, straight from MuJoCo's compiled model.
    let rig = Rig::new(
        Path::new(DEFAULT_MODEL),
        Vec::new(),
        &Faults::default(),
        &Faults::default(),
    )
    .unwrap();
    let model = rig.sim().physics().model();
    let mut hinges: Vec<String> = (0..model.ffi().njnt as usize)
        .filter(|&j| model.jnt_type()[j] == mujoco_rs::wrappers::mj_model::MjtJoint::mjJNT_HINGE)
        .map(|j| {
            model
                .id_to_name(mujoco_rs::wrappers::mj_model::MjtObjBase::mjOBJ_JOINT, j)
                .unwrap()
                .to_owned()
        })
        .collect();
    hinges.sort();
    assert_eq!(movable, hinges);
    assert_eq!(hinges.len(), 18);
    assert!(robot.links.iter().any(|l| l.name == ROOT_BODY));
}

#[test]
fn the_transform_chain_puts_every_link_where_mujoco_has_its_body() {
    let model = Path::new(DEFAULT_MODEL);
    let mut rig = Rig::new(model, plan(), &Faults::default(), &Faults::default()).unwrap();
    rig.run_until(3.3).unwrap();
    let physics = rig.sim().physics();
    let qpos = physics.data().qpos();
    let tree = RobotTree::of(physics.model(), ROOT_BODY).unwrap();
    // MuJoCo's own body poses for this state, from a model of its own.
    let (fresh, _) = sim_host::robot::model::load(model).unwrap();
    let mut data = fresh.make_data();
    data.qpos_mut().copy_from_slice(qpos);
    data.kinematics();
    let mut world: BTreeMap<String, Pose> = BTreeMap::new();
    world.insert(tree.root.clone(), tree.root_pose(qpos).unwrap());
    let mut worst_m: f64 = 0.0;
    let mut worst_q: f64 = 0.0;
    let mut checked = 0;
    for link in &tree.links {
        let pose = world[&link.parent].then(&RobotTree::link_pose(link, qpos));
        if let Some(body) = link.body {
            let (xpos, xquat) = (data.xpos()[body], data.xquat()[body]);
            for (chained, own) in pose.translation_m.iter().zip(xpos) {
                worst_m = worst_m.max((chained - own).abs());
            }
            // q and −q are the same rotation.
            let dot: f64 = (0..4).map(|k| pose.rotation_wxyz[k] * xquat[k]).sum();
            worst_q = worst_q.max(1.0 - dot.abs());
            checked += 1;
        }
        world.insert(link.name.clone(), pose);
    }
    println!("MEASURED transform chain vs MuJoCo over {checked} bodies: {worst_m:e} m, 1−|q·q'| {worst_q:e}");
    assert_eq!(
        checked, 18,
        "every body below the torso: 2 wheels, 4 legs of 4"
    );
    assert!(worst_m < 1e-9 && worst_q < 1e-12, "{worst_m} {worst_q}");
}

/// A port nothing listens on now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

#[test]
fn a_live_client_receives_joint_states_at_50_hz_or_more() {
    use tungstenite::client::IntoClientRequest;
    use tungstenite::Message;

    let port = free_port();
    let mut cfg = config(Plant::default(), plan(), Vec::new(), 6.0);
    cfg.max_speed = Some(1.0);
    cfg.live_port = Some(port);
    let run = std::thread::spawn(move || session::run(&cfg).map(|r| r.stats.cycles));
    let mut request = format!("ws://127.0.0.1:{port}")
        .into_client_request()
        .unwrap();
    request
        .headers_mut()
        .insert("sec-websocket-protocol", "foxglove.sdk.v1".parse().unwrap());
    let started = Instant::now();
    let mut socket = loop {
        match tungstenite::connect(request.clone()) {
            Ok((socket, _)) => break socket,
            Err(e) if started.elapsed() < Duration::from_secs(5) => {
                let _ = e;
                std::thread::sleep(Duration::from_millis(20));
            }
            Err(e) => panic!("no live server on {port}: {e}"),
        }
    };
    // The advertisement names the channels; subscribe to the joint states.
    let channel = loop {
        let Message::Text(text) = socket.read().unwrap() else {
            continue;
        };
        let message: serde_json::Value = serde_json::from_str(&text).unwrap();
        if message["op"] != "advertise" {
            continue;
        }
        if let Some(c) = message["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["topic"] == "/joint_states")
        {
            break c["id"].as_u64().unwrap();
        }
    };
    let subscribe = serde_json::json!({
        "op": "subscribe",
        "subscriptions": [{"id": 7, "channelId": channel}],
    });
    socket.send(Message::text(subscribe.to_string())).unwrap();
    let window = Duration::from_secs(2);
    let mut received = 0;
    let mut first: Option<Instant> = None;
    while first.is_none_or(|at| at.elapsed() < window) {
        if let Message::Binary(bytes) = socket.read().unwrap() {
            // Op 1 (message data), then the subscription id.
            if bytes.first() == Some(&1) && bytes.get(1..5) == Some(&7_u32.to_le_bytes()[..]) {
                // After the op, subscription and time: the message, naming the 18 joints.
                let payload = &bytes[13..];
                assert!(
                    payload.windows(7).any(|w| w == b"knee_fl"),
                    "{} bytes",
                    payload.len()
                );
                first.get_or_insert_with(Instant::now);
                received += 1;
            }
        }
    }
    let rate_hz = f64::from(received) / window.as_secs_f64();
    println!("MEASURED live joint states: {received} in {window:?} ({rate_hz:.0} Hz)");
    drop(socket);
    let cycles = run.join().unwrap().unwrap();
    assert!(cycles > 0);
    assert!(rate_hz >= 50.0, "{rate_hz} Hz");
}
