//! The interactive MuJoCo viewer on a run (feature `viewer`): mujoco-rs's passive viewer, fed a
//! copy of the simulation state every control cycle.
//!
//! The viewer watches; it does not act. It draws a private copy of the state
//! ([`MjData::copy_visual_to`]), so mouse perturbations and resets made in its window do not
//! reach the simulation, whose actuators belong to the emulated CAN drives.
//!
//! It needs a desktop session (X11 or Wayland) with OpenGL, and must be opened on the main
//! thread. Where there is none (CI, SSH without forwarding), [`Viewer::open`] returns
//! [`ViewerError::NoDisplay`]; headless frames are the `renderer` feature's job.

use crate::error_chain::chain;
use std::panic::{self, AssertUnwindSafe};
use std::time::{Duration, Instant};

use mujoco_rs::error::MjDataError;
use mujoco_rs::prelude::{MjData, MjModel};
use mujoco_rs::viewer::{MjViewer, MjViewerError};

use crate::robot::physics::Physics;
use crate::session::simulator::Simulator;

/// Shortest wall-clock time between two drawn frames (60 frames per second): syncing is cheap
/// and happens every cycle, drawing is not and would slow a 250 Hz real-time run.
pub const MIN_FRAME_INTERVAL: Duration = Duration::from_nanos(1_000_000_000 / 60);

/// Why the viewer could not be opened or updated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// No display server to open a window on.
    #[error("the viewer needs a display, but neither DISPLAY nor WAYLAND_DISPLAY is set: run it in a desktop session (or with X forwarding); for headless frames use `--render-every N` (sim-host built with `--features renderer`)")]
    NoDisplay,
    /// Windows can only be opened on the main thread.
    #[error("the viewer must be opened on the program's main thread")]
    NotMainThread,
    /// The window or its OpenGL context could not be created.
    #[error("cannot open the viewer window: {}; it needs a desktop session (X11 or Wayland) with OpenGL (Debian/Ubuntu with Mesa: libegl1 libgl1-mesa-dri libglx-mesa0)", chain(.source))]
    Open {
        /// What mujoco-rs reported.
        source: MjViewerError,
    },
    /// mujoco-rs panicked while opening the window (it does when the display offers no usable
    /// OpenGL configuration).
    #[error("cannot open the viewer window: {message}; the display offers no usable OpenGL configuration (check `glxinfo -B` / `eglinfo`)")]
    OpenPanicked {
        /// The panic message.
        message: String,
    },
    /// Drawing a frame failed.
    #[error("the viewer failed to draw: {}", chain(.source))]
    Draw {
        /// What mujoco-rs reported.
        source: MjViewerError,
    },
    /// The physics is not the model the viewer was opened for.
    #[error("the viewer was opened for another model: {source}")]
    OtherModel {
        /// What mujoco-rs reported.
        source: MjDataError,
    },
}

/// Whether the environment names a display server winit can connect to.
fn display_available() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"]
        .iter()
        .any(|name| std::env::var_os(name).is_some_and(|v| !v.is_empty()))
}

/// An open viewer window showing one model.
pub struct Viewer {
    viewer: MjViewer,
    /// What the viewer shows: a visual copy of the physics' state.
    mirror: MjData<Box<MjModel>>,
    last_drawn: Option<Instant>,
}

impl std::fmt::Debug for Viewer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Viewer")
            .field("running", &self.viewer.running())
            .finish_non_exhaustive()
    }
}

impl Viewer {
    /// Opens a window showing `model`. Call on the main thread.
    ///
    /// # Errors
    /// [`ViewerError::NoDisplay`] without a display server, [`ViewerError::NotMainThread`],
    /// [`ViewerError::Open`] / [`ViewerError::OpenPanicked`] when the window or its OpenGL
    /// context cannot be created.
    pub fn open(model: &MjModel) -> Result<Self, ViewerError> {
        if !display_available() {
            return Err(ViewerError::NoDisplay);
        }
        // winit refuses (by panicking) to create its event loop on another thread on Linux.
        if std::thread::current().name() != Some("main") {
            return Err(ViewerError::NotMainThread);
        }
        let builder = MjViewer::builder().window_name("sim-host: hybrid wheel-leg robot");
        // mujoco-rs panics (rather than returning an error) when the display reports no usable
        // OpenGL configuration; turn that into an error as well.
        let opened = panic::catch_unwind(AssertUnwindSafe(|| builder.build_passive(model)))
            .map_err(|payload| ViewerError::OpenPanicked {
                message: payload
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_owned())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown panic".to_owned()),
            })?;
        let viewer = opened.map_err(|source| ViewerError::Open { source })?;
        Ok(Self {
            viewer,
            mirror: MjData::new(Box::new(model.clone())),
            last_drawn: None,
        })
    }

    /// Syncs the viewer with `sim`'s physics; see [`Viewer::sync`]. Returns `false` once the
    /// window has been closed.
    ///
    /// # Errors
    /// As [`Viewer::sync`].
    pub fn observe(&mut self, sim: &Simulator) -> Result<bool, ViewerError> {
        self.sync(sim.physics())
    }

    /// Copies `physics`' state into the viewer (every call) and draws it and handles the
    /// window's input if [`MIN_FRAME_INTERVAL`] has passed since the last frame. Returns `false`
    /// once the window has been closed.
    ///
    /// # Errors
    /// [`ViewerError::OtherModel`] if `physics` is not the viewer's model, [`ViewerError::Draw`].
    pub fn sync(&mut self, physics: &Physics) -> Result<bool, ViewerError> {
        if !self.viewer.running() {
            return Ok(false);
        }
        physics
            .data()
            .copy_visual_to(&mut self.mirror)
            .map_err(|source| ViewerError::OtherModel { source })?;
        self.viewer.sync_data(&mut self.mirror);
        if self
            .last_drawn
            .is_none_or(|at| at.elapsed() >= MIN_FRAME_INTERVAL)
        {
            self.last_drawn = Some(Instant::now());
            self.viewer
                .render()
                .map_err(|source| ViewerError::Draw { source })?;
        }
        Ok(self.viewer.running())
    }

    /// Keeps drawing the last state, at [`MIN_FRAME_INTERVAL`], until the window is closed (so
    /// that a run faster than real time can still be looked at).
    ///
    /// # Errors
    /// [`ViewerError::Draw`].
    pub fn hold(&mut self) -> Result<(), ViewerError> {
        while self.viewer.running() {
            self.viewer
                .render()
                .map_err(|source| ViewerError::Draw { source })?;
            std::thread::sleep(MIN_FRAME_INTERVAL);
        }
        Ok(())
    }

    /// Whether the window is still open.
    pub fn running(&self) -> bool {
        self.viewer.running()
    }
}
