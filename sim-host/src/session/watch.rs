//! What watches a run besides the progress bar: rendered frames (feature `renderer`) and the
//! interactive viewer (feature `viewer`).

use std::path::PathBuf;

use crate::session::config::SessionConfig;
use crate::session::error::SessionError;
use crate::session::simulator::Simulator;

/// The animation plays at twice the simulation's speed: each frame shows half the simulated time
/// between two frames, hundredths of a second (at least 2: browsers slow faster GIFs down).
#[cfg(feature = "renderer")]
fn animation_delay_cs(config: &SessionConfig) -> u16 {
    let every = config.frames.as_ref().map_or(1, |f| f.every_cycles.get());
    let seconds = f64::from(every) / f64::from(config.control_hz.max(1));
    (seconds * 100.0 / 2.0).round().clamp(2.0, 6000.0) as u16
}

/// What watches a run besides the progress bar: frames (feature `renderer`) and the viewer
/// (feature `viewer`).
#[derive(Debug, Default)]
pub(crate) struct Watch {
    #[cfg(feature = "renderer")]
    frames: Option<crate::output::render::FrameRenderer>,
    #[cfg(feature = "viewer")]
    viewer: Option<crate::output::viewer::Viewer>,
}

impl Watch {
    /// Opens what `config` asks for and renders the starting frame.
    pub(crate) fn open(
        config: &SessionConfig,
        sim: &Simulator,
        camera: Option<std::sync::Arc<foxglove::Channel<crate::output::foxglove::CompressedImage>>>,
    ) -> Result<Self, SessionError> {
        #[allow(unused_mut)]
        let mut watch = Self::default();
        if let Some(frames) = &config.frames {
            #[cfg(feature = "renderer")]
            {
                let mut options =
                    crate::output::render::FrameOptions::chase(&frames.dir, frames.every_cycles);
                options.animation = Some((frames.animation_path(), animation_delay_cs(config)));
                let mut renderer =
                    crate::output::render::FrameRenderer::new(sim.physics().model(), options)?;
                if let Some(camera) = camera {
                    renderer.publish_to(camera);
                }
                renderer.render(sim.physics())?;
                watch.frames = Some(renderer);
            }
            #[cfg(not(feature = "renderer"))]
            {
                let _ = (frames, camera);
                return Err(SessionError::NotBuilt {
                    what: "rendering frames",
                    feature: "renderer",
                });
            }
        }
        if config.viewer {
            #[cfg(feature = "viewer")]
            {
                watch.viewer = Some(crate::output::viewer::Viewer::open(sim.physics().model())?);
            }
            #[cfg(not(feature = "viewer"))]
            return Err(SessionError::NotBuilt {
                what: "the viewer",
                feature: "viewer",
            });
        }
        let _ = sim;
        Ok(watch)
    }

    /// After a cycle: renders a frame if one is due, syncs the viewer. `false`: the viewer was
    /// closed, end the run.
    pub(crate) fn cycle(&mut self, sim: &Simulator) -> Result<bool, SessionError> {
        #[cfg(feature = "renderer")]
        if let Some(frames) = &mut self.frames {
            frames.observe(sim)?;
        }
        #[cfg(feature = "viewer")]
        if let Some(viewer) = &mut self.viewer {
            return Ok(viewer.observe(sim)?);
        }
        let _ = sim;
        Ok(true)
    }

    /// After the run: keeps the viewer open until it is closed; returns the frames written.
    pub(crate) fn finish(self) -> Result<Vec<PathBuf>, SessionError> {
        #[cfg(feature = "viewer")]
        if let Some(mut viewer) = self.viewer {
            if viewer.running() {
                tracing::info!("run finished: close the viewer window to exit");
            }
            viewer.hold()?;
        }
        #[cfg(feature = "renderer")]
        if let Some(frames) = self.frames {
            return Ok(frames.finish()?);
        }
        Ok(Vec::new())
    }
}
