//! The interactive loop: crossterm keys (and a gamepad's actions) in, the operator's frames out on the bus, the bus heard
//! and drawn with ratatui. It polls without blocking so that the 50 Hz heartbeat never waits on
//! the keyboard or the screen. On quit it sends a STOP command before it goes silent.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use host_can::bus::Bus;
use ratatui::crossterm::event::{self, Event, KeyCode, KeyEventKind, KeyModifiers};
use teleop_core::keys::Key;

use crate::app::{App, SimView};
use crate::gamepad::PadReader;

/// Screen refresh period.
const DRAW_PERIOD: Duration = Duration::from_millis(50);
/// Longest wait for a key between two services of the bus.
const KEY_WAIT: Duration = Duration::from_millis(2);

/// Why the interactive session ended badly.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TerminalError {
    /// The terminal could not be read or drawn (not a terminal? run it in one, or use `send` /
    /// `script`).
    #[error("the terminal failed: {0} (teleop's interactive mode needs a terminal; for scripts use `teleop send` or `teleop script`)")]
    Terminal(#[from] std::io::Error),
    /// A frame could not be encoded (a bug: every value is clamped to its wire range first).
    #[error("a teleop frame could not be encoded: {0:?}")]
    Encode(protocol::EncodeError),
}

/// How the session went.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TerminalReport {
    /// Frames sent.
    pub frames_sent: u64,
    /// Whether the E-stop was still latched at the end.
    pub estop_latched: bool,
}

/// Runs the interactive operator on `bus` until Q, Esc or Ctrl-C (or `stop`). `live` gives the
/// in-process simulator's ground truth, when there is one.
pub fn run(
    bus: &mut dyn Bus,
    bus_name: &str,
    key: protocol::Key,
    mut live: impl FnMut() -> Option<SimView>,
    pad: Option<&mut PadReader>,
    stop: &AtomicBool,
) -> Result<TerminalReport, TerminalError> {
    let mut terminal = ratatui::try_init()?;
    let result = serve(&mut terminal, bus, (bus_name, key), &mut live, pad, stop);
    ratatui::try_restore()?;
    result
}

fn serve(
    terminal: &mut ratatui::DefaultTerminal,
    bus: &mut dyn Bus,
    (bus_name, key): (&str, protocol::Key),
    live: &mut dyn FnMut() -> Option<SimView>,
    mut pad: Option<&mut PadReader>,
    stop: &AtomicBool,
) -> Result<TerminalReport, TerminalError> {
    let start = Instant::now();
    let now_ms = || u64::try_from(start.elapsed().as_millis()).unwrap_or(u64::MAX);
    let mut app = App::with_key(bus_name, key);
    let mut last_error = String::new();
    let mut next_draw = Instant::now();
    while !app.quit_requested() && !stop.load(Ordering::Relaxed) {
        while event::poll(Duration::ZERO)? {
            if let Some(key) = key_of(event::read()?) {
                app.key(now_ms(), key);
            }
        }
        if let Some(pad) = pad.as_deref_mut() {
            for action in pad.poll(Instant::now()) {
                app.pad(now_ms(), action);
            }
        }
        let now = now_ms();
        for error in service_bus(&mut app, bus, now)? {
            if error != last_error {
                app.note(error.clone());
                last_error = error;
            }
        }
        if let Some(view) = live() {
            app.set_sim(view);
        }
        if Instant::now() >= next_draw {
            terminal.draw(|frame| crate::ui::draw(frame, &app, now))?;
            next_draw = Instant::now() + DRAW_PERIOD;
        }
        // Waits for a key, but never past the next heartbeat.
        event::poll(KEY_WAIT)?;
    }
    for frame in app.farewell(now_ms()).map_err(TerminalError::Encode)? {
        // Leaving anyway: a failed STOP is covered by the controller's heartbeat watchdog.
        let _ = bus.send(&frame);
    }
    Ok(TerminalReport {
        frames_sent: app.frames_sent(),
        estop_latched: app.operator().estop_latched(),
    })
}

/// One pass's work on the bus at `now_ms`: sends the frames due (an E-stop latch among them),
/// then reads what came, at most [`crate::MAX_FRAMES_PER_PASS`] frames, so that a bus that
/// never runs dry cannot keep the loop from the keys. Returns the bus errors met, for the log.
pub fn service_bus(
    app: &mut App,
    bus: &mut dyn Bus,
    now_ms: u64,
) -> Result<Vec<String>, TerminalError> {
    let frames = app.poll(now_ms).map_err(TerminalError::Encode)?;
    let mut errors = Vec::new();
    for frame in &frames {
        if let Err(e) = bus.send(frame) {
            errors.push(format!("send failed: {e}"));
        }
    }
    for _ in 0..crate::MAX_FRAMES_PER_PASS {
        match bus.recv(Duration::ZERO) {
            Ok(Some(frame)) => app.observe(now_ms, &frame),
            Ok(None) => break,
            Err(e) => {
                errors.push(format!("receive failed: {e}"));
                break;
            }
        }
    }
    Ok(errors)
}

/// The key of a terminal event; Ctrl-C is Esc (quit) since raw mode swallows the signal.
pub fn key_of(event: Event) -> Option<Key> {
    let Event::Key(key) = event else {
        return None;
    };
    if key.kind != KeyEventKind::Press {
        return None;
    }
    match key.code {
        KeyCode::Char('c') if key.modifiers.contains(KeyModifiers::CONTROL) => Some(Key::Esc),
        KeyCode::Char(c) => Some(Key::Char(c)),
        KeyCode::Up => Some(Key::Up),
        KeyCode::Down => Some(Key::Down),
        KeyCode::Left => Some(Key::Left),
        KeyCode::Right => Some(Key::Right),
        KeyCode::Esc => Some(Key::Esc),
        _ => None,
    }
}
