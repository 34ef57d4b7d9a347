//! The screen: what the operator commands, what the controller and the drives report, the bus
//! traffic, the simulator's ground truth (in-process only), the keys, and a banner over all of
//! it when something needs the operator's attention (E-stop, silent controller or drives).

use protocol::{DriveFlags, FaultFlags, RejectCause};
use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::text::{Line, Span};
use ratatui::widgets::{Block, Paragraph, Wrap};
use ratatui::Frame;
use teleop_core::bus_status::SILENT_MS;

use crate::app::{mode_text, App};

/// The keys, as the help line shows them.
pub const KEY_HELP: &str = "W/S wheels fwd/back · A rotate · L/K trot fwd/back · X stop · \
T stand · F fold · H auto · ←/→ steer · ↑/↓ height · ]/[ speed · space E-STOP · R R release · Q quit";

/// Draws the whole screen for time `now_ms`.
pub fn draw(frame: &mut Frame, app: &App, now_ms: u64) {
    let banners = banners(app, now_ms);
    let sim_rows = if app.sim().is_some() { 3 } else { 0 };
    let [title, banner, command, middle, bus, sim, log, keys] = Layout::vertical([
        Constraint::Length(1),
        Constraint::Length(banners.len() as u16),
        Constraint::Length(4),
        Constraint::Length(8),
        Constraint::Length(4),
        Constraint::Length(sim_rows),
        Constraint::Min(3),
        Constraint::Length(4),
    ])
    .areas(frame.area());
    frame.render_widget(
        Paragraph::new(Line::from(vec![
            Span::styled("teleop", Style::new().add_modifier(Modifier::BOLD)),
            Span::raw(format!(" · bus {}", app.bus_name())),
        ])),
        title,
    );
    frame.render_widget(Paragraph::new(banners), banner);
    draw_command(frame, command, app, now_ms);
    let [controller, drives] =
        Layout::horizontal([Constraint::Percentage(50), Constraint::Percentage(50)]).areas(middle);
    draw_controller(frame, controller, app, now_ms);
    draw_drives(frame, drives, app);
    draw_bus(frame, bus, app, now_ms);
    if let Some(view) = app.sim() {
        let text = format!(
            "t {:.1} s   x {:+.2} m   y {:+.2} m   yaw {:+.0}°   height {:.3} m   tilt {:.1}°",
            view.time_s,
            view.position_m[0],
            view.position_m[1],
            view.yaw_deg,
            view.height_m,
            view.tilt_deg
        );
        frame.render_widget(
            Paragraph::new(text).block(Block::bordered().title("Simulator (ground truth)")),
            sim,
        );
    }
    let lines: Vec<Line> = app.log().map(Line::from).collect();
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title("Events")),
        log,
    );
    frame.render_widget(
        Paragraph::new(KEY_HELP)
            .wrap(Wrap { trim: true })
            .block(Block::bordered().title("Keys")),
        keys,
    );
}

fn banners(app: &App, now_ms: u64) -> Vec<Line<'static>> {
    let alarm = Style::new()
        .fg(Color::White)
        .bg(Color::Red)
        .add_modifier(Modifier::BOLD);
    let mut lines = Vec::new();
    // What the controller reports, not only what this program asked for: a latch may be lost
    // on the way (it is resent until confirmed), and another node may have latched one.
    let controller_estop = app
        .status()
        .controller(now_ms)
        .is_some_and(|status| status.mode == protocol::ControllerMode::EStop);
    if controller_estop {
        lines.push(Line::styled(
            " E-STOP LATCHED, confirmed by the controller: the drives stop. Press R twice to release. ",
            alarm,
        ));
    } else if app.operator().estop_latched() {
        lines.push(Line::styled(
            " E-STOP SENT, not yet confirmed by the controller: sending it again every 4 ms. ",
            alarm,
        ));
    }
    if app.status().controller_silent(now_ms) {
        let age = silence(app.status().controller_age_ms(now_ms));
        lines.push(Line::styled(
            format!(
                " CONTROLLER SILENT ({age}): is the firmware running on {}? ",
                app.bus_name()
            ),
            alarm,
        ));
    }
    if app.status().drives_silent(now_ms) {
        let age = silence(app.status().feedback_age_ms(now_ms));
        lines.push(Line::styled(
            format!(
                " DRIVES SILENT ({age}): no joint or wheel feedback on {} ",
                app.bus_name()
            ),
            alarm,
        ));
    }
    lines
}

/// How long a node has been silent, for its banner.
fn silence(age_ms: Option<u64>) -> String {
    age_ms.map_or("never heard".to_owned(), |ms| format!("silent for {ms} ms"))
}

fn draw_command(frame: &mut Frame, area: Rect, app: &App, now_ms: u64) {
    let op = app.operator();
    let heartbeat = app
        .heartbeat_age_ms(now_ms)
        .map_or("not yet sent".to_owned(), |ms| format!("sent {ms} ms ago"));
    let lines = vec![
        Line::from(format!(
            "command {}   height {:+.2} m   speed {:.0} %   steer {:+.2} rad/s",
            mode_text(op.mode()),
            op.body_height_m(),
            op.speed_scale_pct(),
            op.yaw_rate_rad_s()
        )),
        Line::from(format!(
            "heartbeat {heartbeat} (50 Hz)   frames sent {}",
            app.frames_sent()
        )),
    ];
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title("Operator")),
        area,
    );
}

fn draw_controller(frame: &mut Frame, area: Rect, app: &App, now_ms: u64) {
    let lines = match app.status().controller(now_ms) {
        Some(status) => {
            let pitch_deg = status.pitch.si().to_degrees();
            let roll_deg = status.roll.si().to_degrees();
            vec![
                Line::from(format!("mode   {}", status.mode.label())),
                Line::from(format!("faults {}", fault_text(status.faults))),
                Line::from(format!(
                    "tilt   pitch {pitch_deg:+.1}°  roll {roll_deg:+.1}°"
                )),
                Line::from(format!("height {:+.3} m", status.body_height.si())),
                Line::from(format!(
                    "status {} ms ago",
                    app.status().controller_age_ms(now_ms).unwrap_or(0)
                )),
            ]
        }
        None => vec![Line::from(format!("no status for {SILENT_MS} ms or more"))],
    };
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title("Controller")),
        area,
    );
}

fn draw_drives(frame: &mut Frame, area: Rect, app: &App) {
    let names = ["FL", "FR", "BL", "BR", "wheels"];
    let mut lines: Vec<Line> = names
        .iter()
        .zip(app.status().drive_flags())
        .map(|(name, flags)| Line::from(format!("{name:<6} {}", drive_text(flags))))
        .collect();
    if let Some([left, right]) = app.status().wheel_speed_rad_s() {
        lines.push(Line::from(format!(
            "speed  L {left:+.2}  R {right:+.2} rad/s"
        )));
    }
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title("Drives")),
        area,
    );
}

fn draw_bus(frame: &mut Frame, area: Rect, app: &App, now_ms: u64) {
    let status = app.status();
    // Lost frames go on the first line: seven causes fill the second.
    let (rejected, lost) =
        status
            .rejected()
            .map_or(("no report yet".to_owned(), "?".to_owned()), |r| {
                let causes = [
                    ("unknown id", RejectCause::UnknownId),
                    ("length", RejectCause::WrongLength),
                    ("crc", RejectCause::Crc),
                    ("range", RejectCause::OutOfRange),
                    ("repeated", RejectCause::Repeated),
                    ("sequence", RejectCause::WrongSequence),
                    ("rate limited", RejectCause::RateLimited),
                ];
                let text: Vec<String> = causes
                    .iter()
                    .map(|(name, cause)| format!("{name} {}", r.get(*cause).raw()))
                    .collect();
                (text.join(" · "), r.lost.raw().to_string())
            });
    let lines = vec![
        Line::from(format!(
            "{:.0} frames/s   undecodable {}   controller lost {lost}",
            status.frames_per_s(now_ms),
            status.undecodable()
        )),
        Line::from(format!("controller rejected: {rejected}")),
    ];
    frame.render_widget(
        Paragraph::new(lines).block(Block::bordered().title("Bus")),
        area,
    );
}

fn fault_text(faults: FaultFlags) -> String {
    use protocol::signal::WireField;
    flag_names(FaultFlags::FLAGS, faults.bits().into(), "none")
}

fn drive_text(flags: Option<DriveFlags>) -> String {
    use protocol::signal::WireField;
    flags.map_or("no status".into(), |flags| {
        flag_names(DriveFlags::FLAGS, flags.bits().into(), "torque-free")
    })
}

/// The names of the bits set in `bits` (bit i is `labels[i]`), or `empty` when none is.
fn flag_names(labels: &[&str], bits: u32, empty: &str) -> String {
    let names: Vec<&str> = labels
        .iter()
        .enumerate()
        .filter(|(bit, _)| bits & (1 << bit) != 0)
        .map(|(_, name)| *name)
        .collect();
    if names.is_empty() {
        empty.into()
    } else {
        names.join(", ")
    }
}
