//! The firmware's control core as a node on the in-process bus, stepped on the simulator's
//! thread: the closed loop in one process, still talking only through CAN frames.

use firmware::config::Config;
use firmware::controller::ConfigError;
use firmware::node::Node;
use firmware::time::Tick;

use firmware_host::bus::{Bus, BusError};
use firmware_host::inproc_bus::InprocEndpoint;
use std::time::Duration;

/// The firmware node and its bus endpoint.
#[derive(Debug)]
pub struct InprocController {
    node: Node,
    bus: InprocEndpoint,
    rejected: u64,
}

impl InprocController {
    /// The firmware with `config` on `bus`.
    pub fn new(config: Config, bus: InprocEndpoint) -> Result<Self, ConfigError> {
        Ok(Self {
            node: Node::new(config)?,
            bus,
            rejected: 0,
        })
    }

    /// Takes every frame waiting on the bus, runs control tick `tick`, sends its frames.
    pub fn service(&mut self, tick: u32) -> Result<(), BusError> {
        let now = Tick(tick);
        while let Some(frame) = self.bus.recv(Duration::ZERO)? {
            if self.node.on_frame(now, frame.id(), frame.data()).is_err() {
                self.rejected += 1;
            }
        }
        let (_, frames) = self.node.poll(now);
        for frame in &frames {
            self.bus.send(frame)?;
        }
        Ok(())
    }

    /// The firmware node (its controller, counters).
    pub fn node(&self) -> &Node {
        &self.node
    }

    /// Frames the firmware rejected (by cause: [`Node::reject_counters`]).
    pub fn rejected(&self) -> u64 {
        self.rejected
    }
}
