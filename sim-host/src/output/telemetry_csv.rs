//! Telemetry as a CSV file: one header line, then one line per [`TelemetryRow`].

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use protocol::JOINT_NAMES;

use crate::output::output_error::OutputError;
use crate::output::telemetry::TelemetryRow;

/// The CSV's column names, in order: time, torso position and attitude, one `<joint>_rad`
/// column per leg joint in [`JOINT_NAMES`] order, wheel torques and speeds, foot forces, body
/// contact, controller mode.
pub fn header() -> Vec<String> {
    let leading = [
        "time_s",
        "torso_x_m",
        "torso_y_m",
        "torso_z_m",
        "roll_deg",
        "pitch_deg",
        "yaw_deg",
    ];
    let trailing = [
        "wheel_left_torque_nm",
        "wheel_right_torque_nm",
        "wheel_left_speed_rad_s",
        "wheel_right_speed_rad_s",
        "foot_fl_force_n",
        "foot_fr_force_n",
        "foot_bl_force_n",
        "foot_br_force_n",
        "body_contact",
        "mode",
    ];
    let joints = JOINT_NAMES.iter().map(|joint| format!("{joint}_rad"));
    leading
        .iter()
        .map(|name| (*name).to_owned())
        .chain(joints)
        .chain(trailing.iter().map(|name| (*name).to_owned()))
        .collect()
}

/// Telemetry rows streamed to a CSV file as a run goes. Numbers are written in their shortest
/// exact decimal form (`NaN` and `inf` as such); the mode is its
/// [`protocol::ControllerMode::label`], or empty before the first controller status. Rows are
/// buffered: [`CsvWriter::flush`] puts them on disk (the recorder does so every second), and
/// dropping the writer flushes too.
pub struct CsvWriter {
    path: PathBuf,
    writer: csv::Writer<BufWriter<File>>,
    record: Vec<String>,
}

impl std::fmt::Debug for CsvWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CsvWriter")
            .field("path", &self.path)
            .finish()
    }
}

impl CsvWriter {
    /// Creates (or truncates) `path` and writes the [`header`].
    pub fn create(path: &Path) -> Result<Self, OutputError> {
        let file = File::create(path).map_err(|source| io_error(path, source))?;
        let mut writer = csv::Writer::from_writer(BufWriter::new(file));
        let header = header();
        writer
            .write_record(&header)
            .map_err(|source| OutputError::Csv {
                path: path.to_path_buf(),
                source,
            })?;
        Ok(Self {
            path: path.to_path_buf(),
            writer,
            record: Vec::with_capacity(header.len()),
        })
    }

    /// Appends one row.
    pub fn write(&mut self, row: &TelemetryRow) -> Result<(), OutputError> {
        self.record.clear();
        self.record.push(row.time_s.to_string());
        let numbers = row
            .torso_pos_m
            .iter()
            .chain(&row.torso_rpy_deg)
            .chain(&row.leg_joint_rad)
            .chain(&row.wheel_torque_nm)
            .chain(&row.wheel_speed_rad_s)
            .chain(&row.foot_force_n);
        self.record.extend(numbers.map(f64::to_string));
        self.record.push(u8::from(row.body_contact).to_string());
        self.record
            .push(row.mode.map_or("", |mode| mode.label()).to_owned());
        self.writer
            .write_record(&self.record)
            .map_err(|source| OutputError::Csv {
                path: self.path.clone(),
                source,
            })
    }

    /// Puts every row written so far on disk.
    pub fn flush(&mut self) -> Result<(), OutputError> {
        self.writer
            .flush()
            .map_err(|source| io_error(&self.path, source))
    }

    /// Flushes and closes the file.
    pub fn finish(mut self) -> Result<(), OutputError> {
        self.flush()
    }
}

fn io_error(path: &Path, source: std::io::Error) -> OutputError {
    OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `rows` through a [`CsvWriter`] into `path`.
    fn write_csv(path: &Path, rows: &[TelemetryRow]) -> Result<(), OutputError> {
        let mut writer = CsvWriter::create(path)?;
        for row in rows {
            writer.write(row)?;
        }
        writer.finish()
    }
    use protocol::ControllerMode;

    fn row(time_s: f64, mode: Option<ControllerMode>) -> TelemetryRow {
        TelemetryRow {
            time_s,
            torso_pos_m: [1.5, -0.25, 0.3],
            torso_rpy_deg: [0.5, -2.0, 90.0],
            leg_joint_rad: protocol::Joints::from_fn(|i| i as f64 * 0.01),
            wheel_torque_nm: [0.75, -0.125],
            wheel_speed_rad_s: [10.0, 11.0],
            foot_force_n: [0.0; 4],
            body_contact: false,
            mode,
        }
    }

    #[test]
    fn header_names_every_column_in_order() {
        let header = header();
        assert_eq!(header.len(), 7 + 16 + 10);
        assert_eq!(header[0], "time_s");
        assert_eq!(header[6], "yaw_deg");
        assert_eq!(header[7], "hip1_fl_rad");
        assert_eq!(header[22], "ankle_br_rad");
        assert_eq!(header[23], "wheel_left_torque_nm");
        assert_eq!(header[32], "mode");
    }

    #[test]
    fn writes_header_and_one_line_per_row() {
        let dir = std::env::temp_dir().join(format!("telemetry_csv_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("telemetry.csv");
        let rows = [
            row(0.0, None),
            row(0.004, Some(ControllerMode::WheelForward)),
            row(0.008, Some(ControllerMode::Stop)),
        ];
        write_csv(&path, &rows).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), rows.len() + 1);
        assert_eq!(lines[0], header().join(","));
        assert_eq!(lines[0].split(',').count(), 33);
        assert!(lines[1].starts_with("0,1.5,-0.25,0.3,0.5,-2,90,0,0.01,"));
        assert!(lines[1].ends_with(",0.75,-0.125,10,11,0,0,0,0,0,"));
        assert!(lines[2].starts_with("0.004,"));
        assert!(lines[2].ends_with(",WheelForward"));
        assert!(lines[3].ends_with(",Stop"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn no_rows_gives_only_the_header() {
        let dir = std::env::temp_dir().join(format!("telemetry_csv_empty_{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("empty.csv");
        write_csv(&path, &[]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, format!("{}\n", header().join(",")));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unwritable_path_is_an_io_error_naming_the_file() {
        let path = Path::new("/nonexistent-dir-for-test/telemetry.csv");
        let error = write_csv(path, &[row(0.0, None)]).unwrap_err();
        assert!(matches!(&error, OutputError::Io { path: p, .. } if p == path));
        assert!(error
            .to_string()
            .contains("/nonexistent-dir-for-test/telemetry.csv"));
    }
}
