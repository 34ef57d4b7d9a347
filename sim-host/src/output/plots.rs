//! PNG figures of a run: the wheel torques (the report's first figure), the front-left leg's
//! joint angles (its second), the torso's track seen from above, and its height and attitude.
//! Time charts shade the controller's modes and name them.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};

use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;

/// Width and height of every figure, pixels.
pub const SIZE: (u32, u32) = (1000, 500);

/// One figure and the file it is written to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Figure {
    WheelTorque,
    FrontLeftJoints,
    TorsoTrajectory,
    TorsoHeight,
}

impl Figure {
    const ALL: [Figure; 4] = [
        Figure::WheelTorque,
        Figure::FrontLeftJoints,
        Figure::TorsoTrajectory,
        Figure::TorsoHeight,
    ];

    const fn file_name(self) -> &'static str {
        match self {
            Figure::WheelTorque => "wheel_torque.png",
            Figure::FrontLeftJoints => "front_left_joints.png",
            Figure::TorsoTrajectory => "torso_trajectory.png",
            Figure::TorsoHeight => "torso_height.png",
        }
    }
}

const FONT: &str = "sans-serif";
const TITLE_PX: u32 = 22;
const TEXT_PX: u32 = 14;
const MARGIN_PX: u32 = 10;
const X_LABELS_PX: u32 = 40;
const Y_LABELS_PX: u32 = 70;
const LINE_PX: u32 = 2;
const LEGEND_LINE_PX: i32 = 20;
const MARKER_PX: u32 = 6;
const COLORS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

type DrawResult<DB> = Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Draws the four figures of `rows` as [`SIZE`] PNGs in `dir` (created if missing, files
/// overwritten) and returns their paths in this order: `wheel_torque.png` (left and right wheel
/// torque), `front_left_joints.png` (the four front-left joint angles, degrees),
/// `torso_trajectory.png` (x–y top view, start and end marked), `torso_height.png` (height,
/// then pitch and roll). Time charts shade and name the controller's modes. Non-finite values
/// are left out of the lines. Fails with [`OutputError::NoRows`] if `rows` is empty, and with
/// [`OutputError::Io`] or [`OutputError::Plot`] naming the directory or figure that failed.
pub fn write_plots(dir: &Path, rows: &[TelemetryRow]) -> Result<Vec<PathBuf>, OutputError> {
    if rows.is_empty() {
        return Err(OutputError::NoRows);
    }
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut written = Vec::with_capacity(Figure::ALL.len());
    for figure in Figure::ALL {
        let path = dir.join(figure.file_name());
        render(&path, figure, rows).map_err(|message| OutputError::Plot {
            path: path.clone(),
            message,
        })?;
        written.push(path);
    }
    Ok(written)
}

/// Draws `figure` into the PNG `path`, or says why it could not.
fn render(path: &Path, figure: Figure, rows: &[TelemetryRow]) -> Result<(), String> {
    register_fonts().map_err(str::to_owned)?;
    let root = BitMapBackend::new(path, SIZE).into_drawing_area();
    root.fill(&WHITE)
        .and_then(|()| draw(figure, &root, rows))
        .and_then(|()| root.present())
        .map_err(|error| error.to_string())
}

/// Registers the bundled DejaVu Sans as plotters' `sans-serif`, once per process.
fn register_fonts() -> Result<(), &'static str> {
    static REGISTERED: OnceLock<Result<(), &'static str>> = OnceLock::new();
    *REGISTERED.get_or_init(|| {
        register_font(FONT, FontStyle::Normal, dejavu::sans::regular())
            .map_err(|_| "the bundled DejaVu Sans font could not be loaded")
    })
}

fn draw<DB: DrawingBackend>(
    figure: Figure,
    root: &DrawingArea<DB, Shift>,
    rows: &[TelemetryRow],
) -> DrawResult<DB> {
    let modes = mode_spans(rows);
    let series = |label, color, value: fn(&TelemetryRow) -> f64| Line {
        label,
        color,
        points: rows.iter().map(|row| (row.time_s, value(row))).collect(),
    };
    match figure {
        Figure::WheelTorque => {
            let lines = [
                series("left", COLORS[0], |row| row.wheel_torque_nm[0]),
                series("right", COLORS[1], |row| row.wheel_torque_nm[1]),
            ];
            time_chart(
                root,
                "Wheel torque",
                "torque (N·m, + forward)",
                &lines,
                &modes,
            )
        }
        Figure::FrontLeftJoints => {
            let lines = protocol::JOINT_NAMES
                .iter()
                .enumerate()
                .filter(|(_, joint)| joint.ends_with("_fl"))
                .zip(COLORS)
                .map(|((index, joint), color)| Line {
                    label: joint,
                    color,
                    points: rows
                        .iter()
                        .map(|row| {
                            let angle = row.leg_joint_rad.get(index).copied();
                            (row.time_s, angle.unwrap_or(f64::NAN).to_degrees())
                        })
                        .collect(),
                })
                .collect::<Vec<_>>();
            let title = "Front-left leg joint angles";
            time_chart(root, title, "angle (deg)", &lines, &modes)
        }
        Figure::TorsoTrajectory => trajectory_chart(root, rows),
        Figure::TorsoHeight => {
            let (upper, lower) = root.split_vertically(SIZE.1 / 2);
            let height = [series("torso z", COLORS[0], |row| row.torso_pos_m[2])];
            time_chart(&upper, "Torso height", "height (m)", &height, &modes)?;
            let attitude = [
                series("pitch (+ nose down)", COLORS[1], |row| row.torso_rpy_deg[1]),
                series("roll", COLORS[2], |row| row.torso_rpy_deg[0]),
            ];
            time_chart(&lower, "Torso attitude", "angle (deg)", &attitude, &modes)
        }
    }
}

/// One labelled line of (x, y) points.
struct Line<'a> {
    label: &'a str,
    color: RGBColor,
    points: Vec<(f64, f64)>,
}

/// A stretch of time during which the controller reported one mode.
#[derive(Debug, PartialEq)]
struct ModeSpan {
    start_s: f64,
    end_s: f64,
    label: &'static str,
}

/// The modes of `rows`, each from its first row to the next mode's first row (or the last
/// row). Rows without a mode start no span.
fn mode_spans(rows: &[TelemetryRow]) -> Vec<ModeSpan> {
    let end_s = rows.last().map_or(0.0_f64, |row| row.time_s);
    let mut spans: Vec<ModeSpan> = Vec::new();
    let mut current = None;
    for row in rows {
        if row.mode == current {
            continue;
        }
        if let (Some(_), Some(last)) = (current, spans.last_mut()) {
            last.end_s = row.time_s;
        }
        current = row.mode;
        if let Some(mode) = row.mode {
            spans.push(ModeSpan {
                start_s: row.time_s,
                end_s,
                label: mode.label(),
            });
        }
    }
    spans
}

fn time_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    y_desc: &str,
    lines: &[Line],
    modes: &[ModeSpan],
) -> DrawResult<DB> {
    let time = axis_range(lines.iter().flat_map(|line| &line.points).map(|p| p.0), 0.0);
    let values = axis_range(
        lines.iter().flat_map(|line| &line.points).map(|p| p.1),
        0.05,
    );
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, TITLE_PX))
        .margin(MARGIN_PX)
        .x_label_area_size(X_LABELS_PX)
        .y_label_area_size(Y_LABELS_PX)
        .build_cartesian_2d(time.clone(), values.clone())?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc(y_desc)
        .label_style((FONT, TEXT_PX))
        .draw()?;
    let (plot_width, _) = chart.plotting_area().dim_in_pixel();
    let seconds_per_pixel = (time.end - time.start) / f64::from(plot_width.max(1));
    for (index, span) in modes.iter().enumerate() {
        let shade = if index % 2 == 0 { 0.04_f64 } else { 0.10_f64 };
        let band = [(span.start_s, values.start), (span.end_s, values.end)];
        chart.draw_series([Rectangle::new(band, BLACK.mix(shade).filled())])?;
        // About 8 px per character at this size, plus the inset.
        let label_px = 8.0_f64 * (span.label.len() as f64 + 1.0_f64);
        if (span.end_s - span.start_s) / seconds_per_pixel >= label_px {
            let inset: (i32, i32) = (4, 4);
            let text = Text::new(span.label, inset, (FONT, TEXT_PX).into_font().color(&BLACK));
            chart.draw_series([EmptyElement::at((span.start_s, values.end)) + text])?;
        }
    }
    for line in lines {
        let style = line.color.stroke_width(LINE_PX);
        let finite = line.points.iter().copied().filter(|p| p.1.is_finite());
        chart
            .draw_series(LineSeries::new(finite, style))?
            .label(line.label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + LEGEND_LINE_PX, y)], style));
    }
    draw_legend(&mut chart)
}

fn trajectory_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[TelemetryRow],
) -> DrawResult<DB> {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|row| (row.torso_pos_m[0], row.torso_pos_m[1]))
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .collect();
    let x = axis_range(points.iter().map(|p| p.0), 0.05);
    let y = axis_range(points.iter().map(|p| p.1), 0.05);
    // Same metres per pixel on both axes, from the plot area the layout below leaves.
    let (width, height) = area.dim_in_pixel();
    let decorations_px = 100.0_f64;
    let plot = (
        f64::from(width) - decorations_px,
        f64::from(height) - decorations_px,
    );
    let scale = ((x.end - x.start) / plot.0).max((y.end - y.start) / plot.1);
    let (x, y) = (widen(x, scale * plot.0), widen(y, scale * plot.1));
    let mut chart = ChartBuilder::on(area)
        .caption("Torso trajectory (top view)", (FONT, TITLE_PX))
        .margin(MARGIN_PX)
        .x_label_area_size(X_LABELS_PX)
        .y_label_area_size(Y_LABELS_PX)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style((FONT, TEXT_PX))
        .draw()?;
    let style = COLORS[0].stroke_width(LINE_PX);
    chart
        .draw_series(LineSeries::new(points.iter().copied(), style))?
        .label("torso")
        .legend(move |(x, y)| PathElement::new([(x, y), (x + LEGEND_LINE_PX, y)], style));
    let ends = [
        ("start", points.first(), COLORS[2]),
        ("end", points.last(), COLORS[1]),
    ];
    for (label, point, color) in ends {
        if let Some(&point) = point {
            chart
                .draw_series([Circle::new(point, MARKER_PX, color.filled())])?
                .label(label)
                .legend(move |(x, y)| {
                    Circle::new((x + LEGEND_LINE_PX / 2_i32, y), MARKER_PX, color.filled())
                });
        }
    }
    draw_legend(&mut chart)
}

/// The legend box, upper right, as every chart here draws it.
fn draw_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
) -> DrawResult<DB> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FONT, TEXT_PX))
        .draw()
}

/// The range of the finite `values`, widened by `pad` of its span on each side; a point (or
/// nothing) gets a small range around it so the axis is never empty.
fn axis_range(values: impl Iterator<Item = f64>, pad: f64) -> Range<f64> {
    let (low, high) = values
        .filter(|value| value.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(low, high), value| {
            (low.min(value), high.max(value))
        });
    let span = high - low;
    let range = if span > 1e-9_f64 * low.abs().max(high.abs()).max(1.0) {
        (low - pad * span)..(high + pad * span)
    } else {
        let middle = (low + high) / 2.0_f64;
        let half = middle.abs().max(1.0) * 0.1_f64;
        (middle - half)..(middle + half)
    };
    if range.start.is_finite() && range.end.is_finite() {
        range
    } else {
        -1.0..1.0
    }
}

/// `range` widened about its middle to `span`, if that is wider.
fn widen(range: Range<f64>, span: f64) -> Range<f64> {
    let middle = (range.start + range.end) / 2.0_f64;
    let half = span.max(range.end - range.start) / 2.0_f64;
    (middle - half)..(middle + half)
}

#[cfg(test)]
mod tests {
    use super::*;
    use protocol::ControllerMode;

    fn rows(count: usize) -> Vec<TelemetryRow> {
        (0..count)
            .map(|i| {
                let t = i as f64 * 0.004;
                let leg_joint_rad = protocol::Joints::from_fn(|j| (t * 3.0 + j as f64).sin() * 0.5);
                let mode = match i * 3 / count {
                    0 if i < 5 => None,
                    0 => Some(ControllerMode::Stop),
                    1 => Some(ControllerMode::Folding),
                    _ => Some(ControllerMode::WheelForward),
                };
                TelemetryRow {
                    time_s: t,
                    torso_pos_m: [t * 0.3, (t * 2.0).sin() * 0.1, 0.3 + 0.02 * t.cos()],
                    torso_rpy_deg: [t.sin(), 2.0 * t.cos(), 10.0 * t],
                    leg_joint_rad,
                    wheel_torque_nm: [(t * 5.0).sin(), (t * 5.0).cos()],
                    wheel_speed_rad_s: [t, -t],
                    foot_force_n: [0.0; 4],
                    body_contact: false,
                    mode,
                }
            })
            .collect()
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("plots_{name}_{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// (width, height, number of distinct RGB colours) of a PNG.
    fn decode(path: &Path) -> (u32, u32, usize) {
        let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
        let mut reader = decoder.read_info().unwrap();
        let mut buffer = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buffer).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb);
        let pixels = &buffer[..info.buffer_size()];
        let colours: std::collections::HashSet<&[u8]> = pixels.chunks_exact(3).collect();
        (info.width, info.height, colours.len())
    }

    fn assert_pngs(dir: &Path, written: &[PathBuf]) {
        let names = Figure::ALL.map(Figure::file_name);
        assert_eq!(
            names,
            [
                "wheel_torque.png",
                "front_left_joints.png",
                "torso_trajectory.png",
                "torso_height.png"
            ]
        );
        let expected: Vec<PathBuf> = names.iter().map(|name| dir.join(name)).collect();
        assert_eq!(written, expected);
        for path in written {
            let (width, height, colours) = decode(path);
            assert_eq!((width, height), SIZE, "{}", path.display());
            assert!(colours > 10, "{} has {colours} colours", path.display());
        }
    }

    #[test]
    fn writes_four_non_blank_pngs_of_the_right_size() {
        let dir = temp_dir("full");
        let written = write_plots(&dir, &rows(2000)).unwrap();
        assert_pngs(&dir, &written);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn one_row_and_non_finite_values_still_plot() {
        let dir = temp_dir("degenerate");
        let mut rows = rows(1);
        rows[0].wheel_torque_nm = [f64::NAN, f64::INFINITY];
        rows[0].torso_pos_m = [f64::NAN; 3];
        let written = write_plots(&dir, &rows).unwrap();
        assert_pngs(&dir, &written);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn no_rows_is_an_error_and_writes_nothing() {
        let dir = temp_dir("empty");
        assert!(matches!(write_plots(&dir, &[]), Err(OutputError::NoRows)));
        assert!(!dir.exists());
    }

    #[test]
    fn unwritable_directory_is_an_io_error_naming_it() {
        let file = temp_dir("blocker");
        std::fs::write(&file, b"not a directory").unwrap();
        let error = write_plots(&file.join("plots"), &rows(10)).unwrap_err();
        assert!(matches!(&error, OutputError::Io { path, .. } if *path == file.join("plots")));
        std::fs::remove_file(&file).unwrap();
    }

    #[test]
    fn mode_spans_cover_each_mode_until_the_next() {
        let mut rows = rows(6);
        let modes = [
            None,
            Some(ControllerMode::Stop),
            Some(ControllerMode::Stop),
            None,
        ];
        for (row, mode) in rows.iter_mut().zip(modes) {
            row.mode = mode;
        }
        rows[4].mode = Some(ControllerMode::TrotForward);
        rows[5].mode = Some(ControllerMode::TrotForward);
        let span = |start_s, end_s, label| ModeSpan {
            start_s,
            end_s,
            label,
        };
        assert_eq!(
            mode_spans(&rows),
            [span(0.004, 0.012, "Stop"), span(0.016, 0.02, "TrotForward")]
        );
    }

    #[test]
    fn axis_ranges_are_never_empty() {
        assert_eq!(axis_range([0.0, 10.0].into_iter(), 0.05), -0.5..10.5);
        assert_eq!(axis_range([10.0, 10.0].into_iter(), 0.05), 9.0..11.0);
        assert_eq!(axis_range([0.0].into_iter(), 0.05), -0.1..0.1);
        assert_eq!(axis_range([f64::NAN].into_iter(), 0.05), -1.0..1.0);
        assert_eq!(axis_range(std::iter::empty(), 0.0), -1.0..1.0);
        assert_eq!(widen(0.0..1.0, 3.0), -1.0..2.0);
        assert_eq!(widen(0.0..1.0, 0.5), 0.0..1.0);
    }
}
