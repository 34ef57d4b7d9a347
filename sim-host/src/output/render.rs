//! Headless frames of a run (feature `renderer`): a camera of the model rendered offscreen
//! through EGL to numbered PNG files, `frame_00000.png`, `frame_00001.png`, … in one folder.
//!
//! No display and no GPU are needed: on Linux, mujoco-rs opens an EGL pbuffer context on the
//! first EGL device that works, which on a machine without a GPU is Mesa's software rasteriser
//! (llvmpipe). The Debian packages that provide it are `libegl1`, `libegl-mesa0` and
//! `libgl1-mesa-dri`; libEGL is loaded at run time, so building needs none of them. No
//! environment variables are needed: mujoco-rs tries every EGL device, Mesa's software device
//! (which needs no `/dev/dri`) included. On llvmpipe a 640 × 480 frame takes tens of
//! milliseconds, so render every few cycles, not every cycle, in a real-time run.
//!
//! The renderer draws a private copy of the simulation state ([`MjData::copy_visual_to`]), so it
//! only ever reads the [`Physics`] it is given.

use crate::error_chain::chain;
use std::num::NonZeroU32;
use std::path::{Path, PathBuf};

use mujoco_rs::error::MjDataError;
use mujoco_rs::prelude::{MjData, MjModel, MjtObjBase, MjvCamera};
use mujoco_rs::renderer::{png, MjRenderer, RendererError};

use std::sync::Arc;

use foxglove::Channel;

use crate::output::animation::Animation;
use crate::output::foxglove::CompressedImage;
use crate::robot::physics::Physics;
use crate::session::simulator::Simulator;

/// The camera frames are rendered from unless told otherwise: `chase` in `hybrid_robot.xml`,
/// which follows the robot's centre of mass from behind and to the side.
pub const CHASE_CAMERA: &str = "chase";

/// The Debian/Ubuntu packages the EGL software renderer needs.
pub const EGL_PACKAGES: &str = "libegl1 libegl-mesa0 libgl1-mesa-dri";

/// How to render frames.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameOptions {
    /// Folder for the PNG files; created if missing. Existing `frame_*.png` files in it are
    /// overwritten, not removed.
    pub dir: PathBuf,
    /// [`FrameRenderer::observe`] renders a frame whenever the simulator's completed cycle count
    /// is a multiple of this, control cycles.
    pub every_cycles: NonZeroU32,
    /// Name of the model camera to render from.
    pub camera: String,
    /// Frame size (width, height), px; `None`: the model's offscreen buffer size
    /// (`<visual><global offwidth offheight>`, 640 × 480 in `hybrid_robot.xml`). Must fit in
    /// that buffer.
    pub size_px: Option<(u32, u32)>,
    /// Also write every frame, halved, to this animated GIF, each shown this many hundredths of
    /// a second (`None`: no animation).
    pub animation: Option<(PathBuf, u16)>,
}

impl FrameOptions {
    /// Frames of the [`CHASE_CAMERA`] at the model's offscreen size into `dir`, one every
    /// `every_cycles` control cycles.
    pub fn chase(dir: impl Into<PathBuf>, every_cycles: NonZeroU32) -> Self {
        Self {
            dir: dir.into(),
            every_cycles,
            camera: CHASE_CAMERA.to_owned(),
            size_px: None,
            animation: None,
        }
    }
}

/// Why frames could not be rendered.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The model has no camera of that name.
    #[error("the model has no camera named `{camera}`: add one, e.g. <camera name=\"{camera}\" mode=\"trackcom\" pos=\"-1.6 -1.6 1.0\" xyaxes=\"1 -1 0 0.3 0.3 1\"/> on the torso")]
    NoCamera {
        /// The name looked for.
        camera: String,
    },
    /// A frame width or height is zero.
    #[error("frames of {width} x {height} px: width and height must both be positive (set <visual><global offwidth=\"640\" offheight=\"480\"/> in the model)")]
    ZeroSize {
        /// Width asked for, px.
        width: u32,
        /// Height asked for, px.
        height: u32,
    },
    /// The frame is larger than the model's offscreen buffer.
    #[error("frames of {width} x {height} px do not fit the model's offscreen buffer of {max_width} x {max_height} px: raise <visual><global offwidth offheight> in the model")]
    TooLarge {
        /// Width asked for, px.
        width: u32,
        /// Height asked for, px.
        height: u32,
        /// The model's `offwidth`, px.
        max_width: u32,
        /// The model's `offheight`, px.
        max_height: u32,
    },
    /// No headless OpenGL context: EGL or Mesa's drivers are missing or failed.
    #[error("cannot open a headless OpenGL context through EGL ({}); install {EGL_PACKAGES} (Mesa's software renderer needs neither a display nor a GPU)", chain(.source))]
    Egl {
        /// What mujoco-rs reported.
        source: RendererError,
    },
    /// The frame folder could not be created.
    #[error("cannot create the frame folder {}: {source}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Drawing or reading back a frame failed.
    #[error("rendering frame {index} failed: {}", chain(.source))]
    Draw {
        /// Index of the frame.
        index: usize,
        /// What mujoco-rs reported.
        source: RendererError,
    },
    /// Encoding or writing a PNG failed.
    #[error("cannot write the frame {}: {}", path.display(), chain(.source))]
    Write {
        /// The file.
        path: PathBuf,
        /// What mujoco-rs reported.
        source: RendererError,
    },
    /// The animation could not be written.
    #[error("{source}")]
    Animation {
        /// What failed, naming the file.
        #[from]
        source: crate::output::output_error::OutputError,
    },
    /// A frame just written could not be read back for the camera channel.
    #[error("cannot read back the frame {}: {source}", path.display())]
    ReadBack {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The physics is not the model the renderer was made for.
    #[error("the renderer was made for another model: {source}")]
    OtherModel {
        /// What mujoco-rs reported.
        source: MjDataError,
    },
}

/// Renders one model camera offscreen to numbered PNG files.
///
/// Must be created and used on one thread (its OpenGL context is current there).
pub struct FrameRenderer {
    renderer: MjRenderer,
    /// What the renderer draws: a visual copy of the physics' state.
    mirror: MjData<Box<MjModel>>,
    dir: PathBuf,
    every_cycles: NonZeroU32,
    size_px: (u32, u32),
    frames: Vec<PathBuf>,
    animation: Option<Animation>,
    camera: Option<Arc<Channel<CompressedImage>>>,
}

impl std::fmt::Debug for FrameRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrameRenderer")
            .field("dir", &self.dir)
            .field("every_cycles", &self.every_cycles)
            .field("size_px", &self.size_px)
            .field("frames", &self.frames.len())
            .finish_non_exhaustive()
    }
}

impl FrameRenderer {
    /// Opens a headless OpenGL context for `model` and creates `options.dir`.
    ///
    /// # Errors
    /// [`RenderError::NoCamera`], [`RenderError::ZeroSize`], [`RenderError::TooLarge`] for a
    /// model or options that cannot work; [`RenderError::Egl`] when no EGL context opens (the
    /// message names the packages to install); [`RenderError::CreateDir`].
    pub fn new(model: &MjModel, options: FrameOptions) -> Result<Self, RenderError> {
        let camera_id = model
            .name_to_id(MjtObjBase::mjOBJ_CAMERA, &options.camera)
            .ok_or_else(|| RenderError::NoCamera {
                camera: options.camera.clone(),
            })?;
        let global = &model.vis().global;
        let max = (
            u32::try_from(global.offwidth).unwrap_or(0),
            u32::try_from(global.offheight).unwrap_or(0),
        );
        let (width, height) = options.size_px.unwrap_or(max);
        if width == 0 || height == 0 {
            return Err(RenderError::ZeroSize { width, height });
        }
        if width > max.0 || height > max.1 {
            return Err(RenderError::TooLarge {
                width,
                height,
                max_width: max.0,
                max_height: max.1,
            });
        }
        std::fs::create_dir_all(&options.dir).map_err(|source| RenderError::CreateDir {
            path: options.dir.clone(),
            source,
        })?;
        let renderer = MjRenderer::builder()
            .width(width)
            .height(height)
            .rgb(true)
            .depth(false)
            .png_compression(png::Compression::Fast)
            .camera(MjvCamera::new_fixed(camera_id))
            .build(model)
            .map_err(|source| RenderError::Egl { source })?;
        let animation = match &options.animation {
            Some((path, delay_cs)) => Some(Animation::create(path, (width, height), *delay_cs)?),
            None => None,
        };
        Ok(Self {
            camera: None,
            animation,
            renderer,
            mirror: MjData::new(Box::new(model.clone())),
            dir: options.dir,
            every_cycles: options.every_cycles,
            size_px: (width, height),
            frames: Vec::new(),
        })
    }

    /// Also logs every frame (its PNG) on `camera`, stamped with simulation time.
    pub fn publish_to(&mut self, camera: Arc<Channel<CompressedImage>>) {
        self.camera = Some(camera);
    }

    /// Renders a frame if `sim`'s completed cycle count is a multiple of the interval (so
    /// called before the first cycle too, frame `k` shows simulated time
    /// `k · every_cycles / control rate`). Returns the file written, if any.
    ///
    /// # Errors
    /// As [`FrameRenderer::render`].
    pub fn observe(&mut self, sim: &Simulator) -> Result<Option<PathBuf>, RenderError> {
        if sim.cycle() % self.every_cycles.get() != 0 {
            return Ok(None);
        }
        self.render(sim.physics()).map(Some)
    }

    /// Renders the current state of `physics` to the next `frame_NNNNN.png` and returns its
    /// path.
    ///
    /// # Errors
    /// [`RenderError::OtherModel`] if `physics` is not the renderer's model,
    /// [`RenderError::Draw`], [`RenderError::Write`].
    pub fn render(&mut self, physics: &Physics) -> Result<PathBuf, RenderError> {
        let index = self.frames.len();
        physics
            .data()
            .copy_visual_to(&mut self.mirror)
            .map_err(|source| RenderError::OtherModel { source })?;
        self.renderer
            .sync_data(&mut self.mirror)
            .and_then(|()| self.renderer.render())
            .map_err(|source| RenderError::Draw { index, source })?;
        let path = self.dir.join(format!("frame_{index:05}.png"));
        self.renderer
            .save_rgb(&path)
            .map_err(|source| RenderError::Write {
                path: path.clone(),
                source,
            })?;
        self.frames.push(path.clone());
        if let Some(animation) = &mut self.animation {
            let rgb = self.renderer.rgb_flat().unwrap_or(&[]);
            animation.push(rgb)?;
        }
        if let Some(camera) = &self.camera {
            let png = std::fs::read(&path).map_err(|source| RenderError::Animation {
                source: crate::output::output_error::OutputError::Io {
                    path: path.clone(),
                    source,
                },
            })?;
            let time_s = physics.time_s();
            camera.log_with_time(
                &CompressedImage {
                    timestamp: Some(crate::output::foxglove::timestamp(time_s)),
                    frame_id: CHASE_CAMERA.into(),
                    data: png.into(),
                    format: "png".into(),
                },
                crate::output::foxglove::nanos(time_s),
            );
        }
        Ok(path)
    }

    /// The last frame rendered: `width · height` RGB pixels, 8 bits per channel, rows top to
    /// bottom (all zeros before the first frame).
    pub fn rgb(&self) -> &[u8] {
        self.renderer.rgb_flat().unwrap_or(&[])
    }

    /// Frame size (width, height), px.
    pub fn size_px(&self) -> (u32, u32) {
        self.size_px
    }

    /// The folder frames go to.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Every file written so far, in order.
    pub fn frames(&self) -> &[PathBuf] {
        &self.frames
    }

    /// The files written, giving the renderer up (its OpenGL context is freed) and ending the
    /// animation.
    ///
    /// # Errors
    /// [`RenderError::Animation`] when the animation's file cannot be completed.
    pub fn finish(self) -> Result<Vec<PathBuf>, RenderError> {
        if let Some(animation) = self.animation {
            animation.finish()?;
        }
        Ok(self.frames)
    }
}
