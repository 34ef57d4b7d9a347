//! Headless frames through EGL (feature `renderer`): the standing robot rendered from the
//! `chase` camera to PNG files of the configured size that show the scene, torso included.
//!
//! Needs Mesa's EGL (Debian: libegl1 libegl-mesa0 libgl1-mesa-dri); no display, no GPU.
//!
//! One test function only: OpenGL contexts are bound to a thread, and one test keeps the
//! renderers on one thread and their order fixed.
#![cfg(feature = "renderer")]

mod common;

use std::collections::HashSet;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

use sim_host::output::render::{FrameOptions, FrameRenderer, RenderError};
use sim_host::robot::model::DEFAULT_MODEL;
use sim_host::robot::plant::Plant;
use sim_host::session::simulator::{Simulator, StartPose};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sim-host-render-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// (width, height, RGB bytes) of a PNG.
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap();
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Whether a pixel is the torso's blue (rgba 0.2 0.4 0.75, lit and shaded): blue clearly
/// above green clearly above red.
fn torso_blue(p: &[u8]) -> bool {
    let (r, g, b) = (i32::from(p[0]), i32::from(p[1]), i32::from(p[2]));
    b > 60 && b - g > 25 && g - r > 15
}

#[test]
fn frames_of_the_standing_robot_show_the_scene_at_the_configured_size() {
    let mut sim = Simulator::new(
        Path::new(DEFAULT_MODEL),
        250,
        StartPose::standing(),
        Plant::default(),
    )
    .unwrap();

    // A camera the model lacks and a frame larger than the offscreen buffer are refused
    // before any OpenGL is touched.
    let every = NonZeroU32::new(5).unwrap();
    let model = sim.physics().model();
    let mut bad = FrameOptions::chase(scratch("bad"), every);
    bad.camera = "nosuchcamera".to_owned();
    let err = FrameRenderer::new(model, bad).unwrap_err();
    assert!(matches!(err, RenderError::NoCamera { .. }), "{err}");
    assert!(err.to_string().contains("nosuchcamera"), "{err}");
    let mut big = FrameOptions::chase(scratch("big"), every);
    big.size_px = Some((4000, 480));
    let err = FrameRenderer::new(model, big).unwrap_err();
    assert!(matches!(err, RenderError::TooLarge { .. }), "{err}");
    assert!(err.to_string().contains("offwidth"), "{err}");

    let dir = scratch("frames");
    let mut options = FrameOptions::chase(&dir, every);
    options.size_px = Some((320, 240));
    let gif_path = dir.join("run.gif");
    options.animation = Some((gif_path.clone(), 10));
    let mut frames = match FrameRenderer::new(model, options) {
        Ok(frames) => frames,
        Err(e) => panic!("{e}"),
    };
    assert_eq!(frames.size_px(), (320, 240));

    // Frames at cycles 0, 5, 10, 15 (the robot standing, servos holding it).
    assert!(frames.observe(&sim).unwrap().is_some(), "cycle 0 renders");
    for _ in 0..15 {
        sim.advance();
        frames.observe(&sim).unwrap();
    }
    let written = frames.frames().to_vec();
    let names: Vec<_> = written
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        [
            "frame_00000.png",
            "frame_00001.png",
            "frame_00002.png",
            "frame_00003.png"
        ]
    );
    assert!(written.iter().all(|p| p.starts_with(&dir)));

    for path in &written {
        let (width, height, rgb) = decode(path);
        assert_eq!((width, height), (320, 240), "{}", path.display());
        assert_eq!(rgb.len(), 320 * 240 * 3);
        let colours: HashSet<[u8; 3]> = rgb.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        assert!(
            colours.len() > 200,
            "{}: {} distinct colours, looks blank",
            path.display(),
            colours.len()
        );
        let blue = rgb.chunks_exact(3).filter(|p| torso_blue(p)).count();
        assert!(
            blue > 320 * 240 / 100,
            "{}: {blue} torso-blue pixels, the torso is not in view",
            path.display()
        );
    }
    // The in-memory frame is the last file's pixels.
    assert_eq!(frames.rgb(), decode(&written[3]).2.as_slice());

    // The animation: the same frames, halved, each 0.1 s, the torso in view in each.
    assert_eq!(frames.finish().unwrap(), written);
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(std::fs::File::open(&gif_path).unwrap())
        .unwrap();
    assert_eq!((decoder.width(), decoder.height()), (160, 120));
    let mut shown = 0;
    while let Some(frame) = decoder.read_next_frame().unwrap() {
        assert_eq!(frame.delay, 10);
        let blue = frame
            .buffer
            .chunks_exact(4)
            .filter(|p| torso_blue(p))
            .count();
        assert!(
            blue > 160 * 120 / 100,
            "GIF frame {shown}: {blue} torso-blue pixels"
        );
        shown += 1;
    }
    assert_eq!(shown, 4);

    // Full size from the model's offscreen buffer (640 x 480).
    let full_dir = scratch("full");
    let mut full =
        FrameRenderer::new(sim.physics().model(), FrameOptions::chase(&full_dir, every)).unwrap();
    let path = full.render(sim.physics()).unwrap();
    assert_eq!(path, full_dir.join("frame_00000.png"));
    let (width, height, _) = decode(&path);
    assert_eq!((width, height), (640, 480));

    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&full_dir);
    drop(full);
    frames_reach_the_mcap();
}

/// A rendered run's frames are in its MCAP as `/camera` (`foxglove.CompressedImage`), one per
/// frame, read back by the Python `mcap` reader.
fn frames_reach_the_mcap() {
    let out = scratch("mcap");
    let mut config = common::config(Plant::default(), Vec::new(), Vec::new(), 1.0);
    config.out_dir = Some(out.clone());
    config.plots = false;
    config.frames = Some(sim_host::session::FrameSettings {
        dir: out.join("frames"),
        every_cycles: NonZeroU32::new(50).unwrap(),
    });
    let report = sim_host::session::run(&config).unwrap();
    assert_eq!(report.frames.len(), 6, "frames at 0, 0.2, … 1.0 s");
    let read = common::read_mcap(&out.join("run.mcap"));
    let camera = read["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["topic"] == "/camera")
        .unwrap_or_else(|| panic!("no /camera channel: {read}"));
    assert_eq!(camera["schema"], "foxglove.CompressedImage", "{camera}");
    assert_eq!(camera["count"], 6, "{camera}");
    let _ = std::fs::remove_dir_all(&out);
}
