//! A flood of received frames must not starve the operator's keys (issue 17): teleop's loops read
//! at most `MAX_FRAMES_PER_PASS` frames a pass, so a bus that never runs dry still lets each pass
//! end, the next key be read, and the E-stop go out — here to the firmware's own controller node,
//! which must latch it. Before the bound, the first pass read the flood until it ended: never.

use std::sync::atomic::AtomicBool;
use std::sync::mpsc;
use std::time::Duration;

use firmware::control::fsm::State;
use firmware::{Config, Node, Tick};
use host_can::bus::{Bus, BusError};
use protocol::{Epoch, Frame, MessageId, Session, TEST_KEY};
use teleop::app::App;
use teleop::MAX_FRAMES_PER_PASS;
use teleop_core::keys::{Action, Key};

/// A bus with another frame always waiting (a babbling node's junk status frames); what the
/// operator sends goes to a controller node.
struct Flooded {
    controller: Node,
    /// Frames the operator sent.
    sent: Vec<Frame>,
    /// Frames handed to the operator.
    reads: usize,
}

impl Flooded {
    fn new() -> Self {
        let session = Session::owned(TEST_KEY, Epoch::new(1));
        Self {
            controller: Node::new(Config::ROBOT, session).unwrap(),
            sent: Vec::new(),
            reads: 0,
        }
    }

    /// E-stop frames the operator sent.
    fn estops_sent(&self) -> usize {
        self.sent
            .iter()
            .filter(|f| f.id() == MessageId::EStop.raw())
            .count()
    }

    /// The controller's state once it has run a tick on what it heard.
    fn controller_state(&mut self) -> State {
        let _ = self.controller.poll(Tick(1));
        self.controller.controller().state()
    }
}

impl Bus for Flooded {
    fn send(&mut self, frame: &Frame) -> Result<(), BusError> {
        self.sent.push(*frame);
        // A refused frame is the controller's business; the bus carried it.
        let _ = self.controller.on_frame(Tick(0), frame.id(), frame.data());
        Ok(())
    }

    fn recv(&mut self, _timeout: Duration) -> Result<Option<Frame>, BusError> {
        self.reads += 1;
        Ok(Frame::new(MessageId::ControllerStatus.raw(), &[0xA5; 16]))
    }

    fn name(&self) -> &str {
        "flooded"
    }
}

/// Runs `work` on its own thread and returns what it returns, failing the test if it takes
/// longer than `limit` (an unbounded drain never returns).
fn within<T: Send + 'static>(limit: Duration, work: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(work());
    });
    rx.recv_timeout(limit)
        .unwrap_or_else(|_| panic!("still reading the flood after {limit:?}"))
}

#[test]
fn the_terminal_loop_reads_the_e_stop_key_under_a_flood_and_the_controller_latches() {
    let (first_pass_reads, mut bus, app) = within(Duration::from_secs(10), || {
        let mut app = App::new("flooded");
        let mut bus = Flooded::new();
        // A pass under the flood, before any key: it must end for the next key to be read.
        teleop::terminal::service_bus(&mut app, &mut bus, 0).unwrap();
        let first_pass_reads = bus.reads;
        // Space, the E-stop, read between two passes; the next pass sends it.
        app.key(5, Key::Char(' '));
        teleop::terminal::service_bus(&mut app, &mut bus, 5).unwrap();
        (first_pass_reads, bus, app)
    });
    assert_eq!(first_pass_reads, MAX_FRAMES_PER_PASS);
    assert_eq!(bus.reads, 2 * MAX_FRAMES_PER_PASS);
    assert!(app.operator().estop_latched());
    assert_eq!(bus.estops_sent(), 1);
    assert_eq!(bus.controller_state(), State::EStop);
}

#[test]
fn teleop_send_e_stop_keeps_sending_the_latch_under_a_flood_and_ends_on_time() {
    let hold = Duration::from_millis(200);
    let (report, mut bus) = within(Duration::from_secs(10), move || {
        let mut bus = Flooded::new();
        let stop = AtomicBool::new(false);
        let report = teleop::script::send(&mut bus, TEST_KEY, Action::EStop, hold, &stop);
        (report.unwrap(), bus)
    });
    // Every pass ended: the frames heard are whole passes' worth, and the latch (which the
    // junk statuses never confirm) went out again pass after pass.
    assert_eq!(report.frames_heard as usize, bus.reads);
    assert_eq!(bus.reads % MAX_FRAMES_PER_PASS, 0, "{report:?}");
    assert!(bus.estops_sent() >= 2, "{report:?}");
    assert_eq!(bus.controller_state(), State::EStop);
}
