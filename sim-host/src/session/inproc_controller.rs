//! The firmware's control core as a node on the in-process bus, stepped on the simulator's
//! thread: the closed loop in one process, still talking only through CAN frames.
//!
//! The firmware keeps its own tick, one per [`InprocController::service`], as the MCU's timer
//! does: the simulator's clock never reaches it except through SYNC frames, which it only
//! watches to notice a simulator that restarted (its SYNC tick went back).

use firmware::config::Config;
use firmware::control::controller::{ConfigError, Output};
use firmware::node::service::{self, Drain};
use firmware::node::Node;
use firmware::time::Tick;
use host_can::bus::BusError;
use host_can::inproc_bus::InprocEndpoint;
use host_can::port::{BusPort, Wait};

/// Most frames taken per control tick: a bound for a flooded bus, far above what one cycle
/// carries (the rest waits for the next tick).
const RX_LIMIT: u32 = 1 << 20;

/// The firmware node and its bus endpoint.
#[derive(Debug)]
pub struct InprocController {
    node: Node,
    bus: InprocEndpoint,
    tick: Tick,
    rejected: u64,
    last_sync: Option<u32>,
    sim_restarts: u32,
    last_output: Option<Output>,
}

impl InprocController {
    /// The firmware with `config` on `bus`, opening `session`.
    pub fn new(
        config: Config,
        bus: InprocEndpoint,
        session: protocol::Session,
    ) -> Result<Self, ConfigError> {
        Ok(Self {
            node: Node::new(config, session)?,
            bus,
            tick: Tick(0),
            rejected: 0,
            last_sync: None,
            sim_restarts: 0,
            last_output: None,
        })
    }

    /// Takes every frame waiting on the bus, runs one control tick, sends its frames.
    pub fn service(&mut self) -> Result<(), BusError> {
        let now = self.tick;
        let mut port = BusPort::new(&mut self.bus, Wait::Never);
        let received = service::receive(&mut self.node, now, &mut port, Drain::All, RX_LIMIT)?;
        self.rejected += u64::from(received.rejected);
        if let Some(tick) = received.sync_tick {
            self.watch_sync(tick);
        }
        let mut port = BusPort::new(&mut self.bus, Wait::Never);
        let sent = service::transmit(&mut self.node, now, &mut port)?;
        self.last_output = Some(sent.output);
        self.tick = now.plus(1);
        Ok(())
    }

    fn watch_sync(&mut self, tick: u32) {
        if self.last_sync.is_some_and(|last| tick <= last) {
            self.sim_restarts += 1;
            tracing::warn!(
                sync_tick = tick,
                "the simulator restarted (its SYNC tick went back); following its new state"
            );
        }
        self.last_sync = Some(tick);
    }

    /// The firmware node (its controller, counters).
    pub fn node(&self) -> &Node {
        &self.node
    }

    /// Frames the firmware rejected (by cause: [`Node::reject_counters`]).
    pub fn rejected(&self) -> u64 {
        self.rejected
    }

    /// What the last tick commanded (`None` before the first).
    pub fn last_output(&self) -> Option<&Output> {
        self.last_output.as_ref()
    }

    /// Times the simulator was seen to restart.
    pub fn sim_restarts(&self) -> u32 {
        self.sim_restarts
    }

    /// The tick the next [`InprocController::service`] computes.
    pub fn tick(&self) -> Tick {
        self.tick
    }
}
