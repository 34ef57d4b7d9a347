//! The simulator's bus and the nodes that share its thread: on the in-process bus the firmware
//! and a scripted operator; over SocketCAN only the operator (the firmware is another process).

use std::cell::Cell;
use std::rc::Rc;

use host_can::bus::Bus;
use host_can::inproc_bus::InprocBus;
use host_can::socketcan_bus::SocketCanBus;
use protocol::MessageId;
use protocol::RejectCause;
use protocol::{Epoch, Session, TEST_KEY};
use teleop_core::scripted::ScriptedTeleop;

use crate::session::config::{firmware_config, BusChoice, SessionConfig};
use crate::session::error::SessionError;
use crate::session::inproc_controller::InprocController;
use crate::session::run_stats::RunError;

/// The in-process firmware's reject counters (by cause) and lost frames, as its node last
/// reported them: written by the peers after each service, read by the segment tracker.
pub(crate) type FirmwareCounters = Rc<Cell<([u64; RejectCause::ALL.len()], u64)>>;

/// The simulator's connection to the bus and the nodes that run on its thread.
pub(crate) struct Nodes {
    /// The simulator's own connection.
    pub(crate) sim: Box<dyn Bus>,
    /// The scripted operator's connection (send only), if it has a plan.
    pub(crate) teleop: Option<Box<dyn Bus>>,
    /// The firmware, on the in-process bus only.
    pub(crate) controller: Option<InprocController>,
}

impl Nodes {
    /// Joins the bus `config` names, with the firmware on it when it is in-process.
    pub(crate) fn join(config: &SessionConfig) -> Result<Self, SessionError> {
        let has_teleop = !config.teleop_plan.is_empty();
        Ok(match &config.bus {
            BusChoice::Inproc => {
                let bus = config
                    .attach
                    .as_ref()
                    .map_or_else(InprocBus::new, |a| a.bus.clone());
                let firmware = firmware_config(config.control_hz)
                    .ok_or(SessionError::ControlRate(config.control_hz))?;
                let session = Session::owned(TEST_KEY, epoch_now());
                let controller = InprocController::new(firmware, bus.endpoint(), session)
                    .map_err(SessionError::Firmware)?;
                let teleop: Option<Box<dyn Bus>> = if has_teleop {
                    Some(Box::new(bus.endpoint()))
                } else {
                    None
                };
                Nodes {
                    sim: Box::new(bus.endpoint()),
                    teleop,
                    controller: Some(controller),
                }
            }
            BusChoice::SocketCan(ifname) => {
                // The scripted operator hears only the controller's announcement and status.
                let teleop: Option<Box<dyn Bus>> = if has_teleop {
                    Some(Box::new(SocketCanBus::open(ifname)?.only(&[
                        MessageId::Announce.raw(),
                        MessageId::ControllerStatus.raw(),
                    ])?))
                } else {
                    None
                };
                Nodes {
                    sim: Box::new(SocketCanBus::open(ifname)?),
                    teleop,
                    controller: None,
                }
            }
        })
    }
}

/// Most frames the scripted operator takes from its bus per cycle.
const TELEOP_RX_LIMIT: usize = 4_096;

/// An epoch for an in-process controller: seconds since 2020-01-01 UTC, so that it grows from
/// run to run as a persisted one does on a robot (every simulated run opens a session no
/// recording of an earlier run belongs to).
pub fn epoch_now() -> Epoch {
    const SINCE_2020_S: u64 = 1_577_836_800;
    let now_s = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    Epoch::new(u32::try_from(now_s.saturating_sub(SINCE_2020_S)).unwrap_or(u32::MAX))
}

/// The nodes beside the simulator, run once per cycle: the operator sends what its plan says
/// for the cycle's time, then the firmware services its bus.
pub(crate) struct Peers {
    pub(crate) teleop_bus: Option<Box<dyn Bus>>,
    pub(crate) teleop: ScriptedTeleop,
    pub(crate) controller: Option<InprocController>,
    pub(crate) period_us: u64,
    pub(crate) counters: FirmwareCounters,
}

impl Peers {
    /// One cycle of the peers.
    pub(crate) fn cycle(&mut self, cycle: u32) -> Result<(), RunError> {
        if let Some(bus) = &mut self.teleop_bus {
            // The operator hears the controller's announcement and status (bounded: a flooded
            // bus leaves the rest for the next cycle).
            for _ in 0..TELEOP_RX_LIMIT {
                let Some(frame) = bus.recv(std::time::Duration::ZERO)? else {
                    break;
                };
                self.teleop.observe(&frame);
            }
            for frame in self.teleop.frames(u64::from(cycle) * self.period_us)? {
                bus.send(&frame)?;
            }
        }
        if let Some(controller) = self.controller.as_mut() {
            controller.service()?;
            let counters = controller.node().reject_counters();
            self.counters.set((
                counters.rejected.map(|n| u64::from(n.raw())),
                u64::from(counters.lost.raw()),
            ));
        }
        Ok(())
    }
}
