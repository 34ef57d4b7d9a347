//! Scenario files: what an operator commands, and when. A user writes them; errors name the file
//! and line.
//!
//! ```toml
//! name = "wheels forward"
//! duration_s = 8.0            # simulated time; the last segment runs until then
//!
//! [[step]]
//! at_s = 0.0
//! mode = "fold"               # W S A L K X (the report's keys), stand, fold, drive, walk, auto
//!
//! [[step]]
//! at_s = 3.0
//! mode = "W"
//! body_height_m = 0.0         # optional, −0.10…+0.12 (default 0)
//! speed_scale_pct = 100       # optional, 0…100 (default 100)
//! yaw_rate_rad_s = 0.3        # optional, −3…3, + left: steers W S L K drive walk (default 0)
//! # speed_m_s = 0.3           # drive and walk only: ground speed, −2…2 m/s (default 0)
//! label = "drive"             # optional name of the segment in the summary
//!
//! [scene]                     # optional: the simulator's ground (sim-host reads it)
//! kind = "step"
//! height_m = 0.06
//! ```

use std::path::{Path, PathBuf};

use protocol::TeleopMode;
use serde::Deserialize;
use toml::Spanned;

use crate::keys::{mode_key, mode_of_key};
use crate::scripted::PlanStep;

/// One operator command and the segment it starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// The command, as the teleop sends it.
    pub plan: PlanStep,
    /// Segment name for the summary.
    pub label: String,
}

/// A parsed scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Its name.
    pub name: String,
    /// Simulated time, s.
    pub duration_s: f64,
    /// Steps, in time order.
    pub steps: Vec<Step>,
}

/// Why a scenario file was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The file could not be read.
    #[error("cannot read the scenario {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not valid TOML or has a wrong field.
    #[error("{}:{line}: {message}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A value is outside what the robot accepts.
    #[error("{}:{line}: {message}", path.display())]
    Value {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong and what is allowed.
        message: String,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScenario {
    name: Option<String>,
    duration_s: Spanned<f64>,
    #[serde(default)]
    step: Vec<Spanned<RawStep>>,
    /// The simulator's ground (`sim_host::scene`), which the simulator reads and checks; an
    /// operator's plan does not depend on it.
    #[allow(dead_code)]
    scene: Option<toml::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStep {
    at_s: Spanned<f64>,
    mode: Spanned<String>,
    body_height_m: Option<Spanned<f64>>,
    speed_scale_pct: Option<Spanned<f64>>,
    speed_m_s: Option<Spanned<f64>>,
    yaw_rate_rad_s: Option<Spanned<f64>>,
    label: Option<String>,
}

/// The modes [`parse_mode`] accepts, as an error message names them.
pub const MODE_NAMES: &str = "W S A L K X, stand, fold, drive, walk or auto";

/// The mode a scenario (or `--drive`) names: the report's keys W S A L K X, `stand`, `fold`,
/// `drive` and `walk` (at a ground speed and yaw rate), and `auto` (the autonomous hybrid
/// mode, `H` in the teleop).
pub fn parse_mode(text: &str) -> Option<TeleopMode> {
    match text.trim().to_ascii_lowercase().as_str() {
        "stand" => Some(TeleopMode::Stand),
        "fold" => Some(TeleopMode::Fold),
        "drive" => Some(TeleopMode::Drive),
        "walk" => Some(TeleopMode::Walk),
        "auto" => Some(TeleopMode::Auto),
        key => {
            let mut chars = key.chars();
            match (chars.next(), chars.next()) {
                (Some(c), None) => mode_of_key(c),
                _ => None,
            }
        }
    }
}

/// The largest ground speed a step may ask for, m/s: the wire's (`protocol::GroundSpeed`); the
/// controller takes less.
const SPEED_LIMIT_M_S: f32 = 2.0;

/// The largest yaw rate a step may ask for, rad/s: the wire's (`protocol::YawRate`).
const YAW_RATE_LIMIT_RAD_S: f32 = 3.0;

/// Whether `mode` follows a ground speed: `drive` and `walk`.
pub const fn takes_speed(mode: TeleopMode) -> bool {
    matches!(mode, TeleopMode::Drive | TeleopMode::Walk)
}

/// Whether a yaw rate steers `mode`: W, S, L, K, `drive` and `walk`.
pub const fn takes_yaw_rate(mode: TeleopMode) -> bool {
    takes_speed(mode)
        || matches!(
            mode,
            TeleopMode::WheelForward
                | TeleopMode::WheelBackward
                | TeleopMode::TrotForward
                | TeleopMode::TrotBackward
        )
}

/// A plan step as a command line gives it (`--drive`): `SECONDS:MODE[,speed=M_S][,yaw=RAD_S]`,
/// e.g. `2:W`, `6:W,yaw=0.3`, `4:drive,speed=0.3,yaw=-0.2`; the same checks as a scenario
/// file's step, with a message naming the part that is wrong.
pub fn parse_drive_step(text: &str) -> Result<PlanStep, String> {
    let (time, rest) = text
        .split_once(':')
        .ok_or_else(|| format!("`{text}`: expected SECONDS:MODE, e.g. 2:W or 4:drive,speed=0.3"))?;
    let seconds: f64 = time
        .trim()
        .parse()
        .map_err(|_| format!("`{time}` is not a number of seconds"))?;
    if !(0.0..=1e6).contains(&seconds) {
        return Err(format!("`{time}`: time must be 0…1e6 s"));
    }
    let mut parts = rest.split(',');
    let mode_text = parts.next().unwrap_or_default();
    let mode = parse_mode(mode_text).ok_or_else(|| format!("`{mode_text}`: use {MODE_NAMES}"))?;
    let mut step = PlanStep::at(seconds, mode);
    for part in parts {
        let (key, value) = part
            .split_once('=')
            .ok_or_else(|| format!("`{part}`: expected speed=M_S or yaw=RAD_S"))?;
        let number = |range: std::ops::RangeInclusive<f32>, unit: &str| {
            value
                .trim()
                .parse::<f32>()
                .ok()
                .filter(|v| range.contains(v))
                .ok_or_else(|| {
                    format!(
                        "`{part}`: give {key} from {} to {} {unit}",
                        range.start(),
                        range.end()
                    )
                })
        };
        match key.trim() {
            "speed" if takes_speed(mode) => {
                step.speed_m_s = number(-SPEED_LIMIT_M_S..=SPEED_LIMIT_M_S, "m/s")?;
            }
            "speed" => return Err(format!("`{part}`: only drive and walk take a speed")),
            "yaw"
                if !matches!(
                    mode,
                    TeleopMode::Stop
                        | TeleopMode::WheelRotate
                        | TeleopMode::Stand
                        | TeleopMode::Fold
                ) =>
            {
                step.yaw_rate_rad_s =
                    number(-YAW_RATE_LIMIT_RAD_S..=YAW_RATE_LIMIT_RAD_S, "rad/s")?;
            }
            "yaw" => return Err(format!("`{part}`: {} ignores a yaw rate", mode_name(mode))),
            other => return Err(format!("`{other}`: expected speed=M_S or yaw=RAD_S")),
        }
    }
    Ok(step)
}

/// The label of a mode in summaries: the report's key, or `stand` / `fold` / `drive` / `walk` /
/// `auto`.
pub fn mode_name(mode: TeleopMode) -> String {
    match mode {
        TeleopMode::Stand => "stand".into(),
        TeleopMode::Fold => "fold".into(),
        TeleopMode::Drive => "drive".into(),
        TeleopMode::Walk => "walk".into(),
        TeleopMode::Auto => "auto".into(),
        other => mode_key(other).map(String::from).unwrap_or_default(),
    }
}

impl Scenario {
    /// Reads and checks `path`.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Read {
            path: path.to_owned(),
            source,
        })?;
        Self::parse(path, &text)
    }

    /// Parses `text` (named `path` in errors).
    pub fn parse(path: &Path, text: &str) -> Result<Self, ScenarioError> {
        let source = Source { path, text };
        let raw: RawScenario = toml::from_str(text).map_err(|e| ScenarioError::Syntax {
            path: path.to_owned(),
            line: e.span().map_or(1, |span| source.line_of(span.start)),
            message: e.message().trim().to_owned(),
        })?;
        let duration_s = *raw.duration_s.get_ref();
        if !(duration_s.is_finite() && duration_s > 0.0 && duration_s <= 86_400.0) {
            return Err(source.value_error(
                raw.duration_s.span().start,
                format!("duration_s = {duration_s}: give 0 < duration_s ≤ 86400 s"),
            ));
        }
        if raw.step.is_empty() {
            return Err(source.value_error(0, "no [[step]]: give at least one command".into()));
        }
        let mut steps = Vec::with_capacity(raw.step.len());
        let mut previous_s = None;
        for step in &raw.step {
            steps.push(source.step(step.get_ref(), duration_s, previous_s)?);
            previous_s = Some(*step.get_ref().at_s.get_ref());
        }
        Ok(Self {
            name: raw.name.unwrap_or_else(|| {
                path.file_stem()
                    .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
            }),
            duration_s,
            steps,
        })
    }

    /// The operator's plan.
    pub fn plan(&self) -> Vec<PlanStep> {
        self.steps.iter().map(|s| s.plan).collect()
    }
}

/// A scenario file's text, for errors that name its line.
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    /// The 1-based line of byte `offset`.
    fn line_of(&self, offset: usize) -> usize {
        self.text.get(..offset).map_or(1, |s| {
            s.lines().count().max(1) + usize::from(s.ends_with('\n'))
        })
    }

    fn value_error(&self, offset: usize, message: String) -> ScenarioError {
        ScenarioError::Value {
            path: self.path.to_owned(),
            line: self.line_of(offset),
            message,
        }
    }

    /// One checked step; `previous_s` is the start of the step before, if any.
    fn step(
        &self,
        s: &RawStep,
        duration_s: f64,
        previous_s: Option<f64>,
    ) -> Result<Step, ScenarioError> {
        let at_s = *s.at_s.get_ref();
        if !(at_s.is_finite() && at_s >= 0.0 && at_s < duration_s) {
            return Err(self.value_error(
                s.at_s.span().start,
                format!("at_s = {at_s}: steps start at 0 ≤ at_s < duration_s ({duration_s} s)"),
            ));
        }
        if let Some(previous_s) = previous_s.filter(|&p| at_s <= p) {
            return Err(self.value_error(
                s.at_s.span().start,
                format!("at_s = {at_s} is not after the previous step's {previous_s} s"),
            ));
        }
        let mode = parse_mode(s.mode.get_ref()).ok_or_else(|| {
            self.value_error(
                s.mode.span().start,
                format!("mode = \"{}\": use {MODE_NAMES}", s.mode.get_ref()),
            )
        })?;
        let body_height_m = self.in_range(&s.body_height_m, -0.10..=0.12, 0.0, |v| {
            format!("body_height_m = {v}: the range is −0.10…+0.12 m")
        })?;
        let speed_scale_pct = self.in_range(&s.speed_scale_pct, 0.0..=100.0, 100.0, |v| {
            format!("speed_scale_pct = {v}: the range is 0…100")
        })?;
        let (speed_m_s, yaw_rate_rad_s) = self.velocity(s, mode)?;
        Ok(Step {
            plan: PlanStep {
                at_us: (at_s * 1e6).round() as u64,
                mode,
                body_height_m: body_height_m as f32,
                speed_scale_pct: speed_scale_pct as f32,
                speed_m_s: speed_m_s as f32,
                yaw_rate_rad_s: yaw_rate_rad_s as f32,
            },
            label: s.label.clone().unwrap_or_else(|| mode_name(mode)),
        })
    }

    /// The step's ground speed and yaw rate, each refused for a mode that ignores it.
    fn velocity(&self, s: &RawStep, mode: TeleopMode) -> Result<(f64, f64), ScenarioError> {
        let name = mode_name(mode);
        if let (Some(v), false) = (&s.speed_m_s, takes_speed(mode)) {
            let message = format!("speed_m_s: mode {name} ignores it; use drive or walk");
            return Err(self.value_error(v.span().start, message));
        }
        if let (Some(v), false) = (&s.yaw_rate_rad_s, takes_yaw_rate(mode)) {
            let message =
                format!("yaw_rate_rad_s: mode {name} ignores it; use W, S, L, K, drive or walk");
            return Err(self.value_error(v.span().start, message));
        }
        let speed_limit = f64::from(SPEED_LIMIT_M_S);
        let speed = self.in_range(&s.speed_m_s, -speed_limit..=speed_limit, 0.0, |v| {
            format!("speed_m_s = {v}: the range is −{speed_limit}…+{speed_limit} m/s")
        })?;
        let yaw_limit = f64::from(YAW_RATE_LIMIT_RAD_S);
        let yaw = self.in_range(&s.yaw_rate_rad_s, -yaw_limit..=yaw_limit, 0.0, |v| {
            format!("yaw_rate_rad_s = {v}: the range is −{yaw_limit}…+{yaw_limit} rad/s")
        })?;
        Ok((speed, yaw))
    }

    /// An optional value, `default` when absent, an error naming it when outside `range`.
    fn in_range(
        &self,
        value: &Option<Spanned<f64>>,
        range: std::ops::RangeInclusive<f64>,
        default: f64,
        message: impl Fn(f64) -> String,
    ) -> Result<f64, ScenarioError> {
        match value {
            Some(v) if !range.contains(v.get_ref()) => {
                Err(self.value_error(v.span().start, message(*v.get_ref())))
            }
            Some(v) => Ok(*v.get_ref()),
            None => Ok(default),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scenario, ScenarioError> {
        Scenario::parse(Path::new("test.toml"), text)
    }

    #[test]
    fn a_scenario_reads_its_steps_in_order() {
        let s = parse(
            "name = \"x\"\nduration_s = 6\n[[step]]\nat_s = 0\nmode = \"fold\"\n[[step]]\nat_s = 2.5\nmode = \"w\"\nspeed_scale_pct = 50\nlabel = \"go\"\n",
        )
        .unwrap();
        assert_eq!(s.steps.len(), 2);
        assert_eq!(s.steps[0].plan.mode, TeleopMode::Fold);
        assert_eq!(s.steps[1].plan.at_us, 2_500_000);
        assert_eq!(s.steps[1].plan.speed_scale_pct, 50.0);
        assert_eq!(s.steps[1].label, "go");
        assert_eq!(s.steps[0].label, "fold");
    }

    #[test]
    fn drive_and_walk_take_a_speed_and_the_moving_keys_a_yaw_rate() {
        let s = parse(
            "duration_s = 9\n[[step]]\nat_s = 0\nmode = \"drive\"\nspeed_m_s = -0.3\nyaw_rate_rad_s = 0.3\n[[step]]\nat_s = 4\nmode = \"L\"\nyaw_rate_rad_s = -0.2\n",
        )
        .unwrap();
        assert_eq!(s.steps[0].plan.mode, TeleopMode::Drive);
        assert_eq!(s.steps[0].plan.speed_m_s, -0.3);
        assert_eq!(s.steps[0].plan.yaw_rate_rad_s, 0.3);
        assert_eq!(s.steps[0].label, "drive");
        assert_eq!(s.steps[1].plan.yaw_rate_rad_s, -0.2);
        assert_eq!(s.steps[1].plan.speed_m_s, 0.0);
    }

    #[test]
    fn a_command_line_step_takes_a_speed_and_a_yaw_rate() {
        let step = parse_drive_step("4:drive,speed=0.3,yaw=-0.2").unwrap();
        assert_eq!(
            (step.mode, step.speed_m_s, step.yaw_rate_rad_s, step.at_us),
            (TeleopMode::Drive, 0.3, -0.2, 4_000_000)
        );
        assert_eq!(parse_drive_step("6:W,yaw=0.3").unwrap().yaw_rate_rad_s, 0.3);
        for (bad, needle) in [
            ("4:W,speed=0.3", "only drive and walk"),
            ("4:A,yaw=0.3", "ignores a yaw rate"),
            ("4:walk,speed=9", "from -2 to 2 m/s"),
            ("4:walk,spin=1", "expected speed=M_S"),
            ("4:Q", "use W S A L K X"),
            ("x:W", "not a number"),
        ] {
            let err = parse_drive_step(bad).unwrap_err();
            assert!(err.contains(needle), "{bad}: {err}");
        }
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"Q\"\n", 4, MODE_NAMES),
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"W\"\n[[step]]\nat_s = 0\nmode = \"X\"\n", 6, "not after"),
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"W\"\nbody_height_m = 0.3\n", 5, "−0.10…+0.12"),
            ("duration_s = 6\n[[step]]\nat_s = 9\nmode = \"W\"\n", 3, "duration_s"),
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"W\"\nspeed = 3\n", 5, "unknown field"),
            ("duration_s = 6\n[[step]\nat_s = 0\n", 2, ""),
            ("duration_s = -1\n[[step]]\nat_s = 0\nmode = \"W\"\n", 1, "0 < duration_s"),
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"W\"\nspeed_m_s = 0.3\n", 5, "use drive or walk"),
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"A\"\nyaw_rate_rad_s = 0.3\n", 5, "ignores it"),
            ("duration_s = 6\n[[step]]\nat_s = 0\nmode = \"drive\"\nspeed_m_s = 3\n", 5, "−2…+2 m/s"),
        ];
        for (text, line, needle) in cases {
            let err = parse(text).unwrap_err();
            let shown = err.to_string();
            assert!(shown.starts_with(&format!("test.toml:{line}: ")), "{shown}");
            assert!(shown.contains(needle), "{shown}");
        }
    }
}
