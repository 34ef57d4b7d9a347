//! Reading a scene: from the command line (`step:height_m=0.08,riser_x_m=1.5`) or from a
//! scenario file's `[scene]` table (`kind = "step"` and the same keys). One set of rules for
//! both; every refusal names where (`--scene`, or the file and line), the key, and what is
//! allowed.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::{Course, Flight, Ramp, Scene, Step};

/// Why a scene was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// No scene of that name.
    #[error("{at}: unknown scene `{kind}`: use flat, step, flight, ramp or course")]
    UnknownKind {
        /// Where it was given.
        at: String,
        /// The name given.
        kind: String,
    },
    /// A `[scene]` table without `kind`.
    #[error("{at}: [scene] needs kind = \"flat\", \"step\", \"flight\", \"ramp\" or \"course\"")]
    MissingKind {
        /// Where the table is.
        at: String,
    },
    /// A key the scene does not have.
    #[error("{at}: the scene `{kind}` has no `{key}`: its keys are {known}")]
    UnknownKey {
        /// Where it was given.
        at: String,
        /// The scene.
        kind: &'static str,
        /// The key given.
        key: String,
        /// The keys it has.
        known: &'static str,
    },
    /// A key given twice.
    #[error("{at}: `{key}` is given twice: give each key once")]
    DuplicateKey {
        /// Where it was given the second time.
        at: String,
        /// The key.
        key: String,
    },
    /// A value that is not a number (or, for `count`, not a whole one; for `side`, not
    /// `ahead` or `behind`).
    #[error("{at}: {key} = {value}: {expected}")]
    NotANumber {
        /// Where it was given.
        at: String,
        /// The key.
        key: String,
        /// The value as given.
        value: String,
        /// What to give.
        expected: &'static str,
    },
    /// A number outside the key's range.
    #[error("{at}: {key} = {value}: give a number from {low} to {high}")]
    OutOfRange {
        /// Where it was given.
        at: String,
        /// The key.
        key: String,
        /// The value given.
        value: f64,
        /// The range.
        low: f64,
        /// The range.
        high: f64,
    },
    /// `--scene` text that is not `KIND` or `KIND:KEY=VALUE,…`.
    #[error("--scene: `{pair}`: write KEY=VALUE, e.g. step:height_m=0.08")]
    NotAPair {
        /// The part that is not `KEY=VALUE`.
        pair: String,
    },
    /// A scenario file that is not valid TOML.
    #[error("{at}: {message}")]
    Toml {
        /// The file and line.
        at: String,
        /// The TOML parser's message.
        message: String,
    },
    /// The robot's model path cannot be made absolute, or is not UTF-8 (MJCF names it as text).
    #[error("the robot model path {}: {reason}", path.display())]
    RobotPath {
        /// The path.
        path: PathBuf,
        /// Why it cannot be named in the scene.
        reason: String,
    },
    /// The scene's MJCF could not be written.
    #[error("cannot write the scene to {}: {source}", path.display())]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

/// One key's value and where it was given: a number, or text that should have been one.
struct Given {
    value: Result<f64, String>,
    at: String,
}

impl Scene {
    /// `KIND` or `KIND:KEY=VALUE,…` as `--scene` takes it.
    pub fn from_arg(text: &str) -> Result<Self, SceneError> {
        let at = || "--scene".to_owned();
        let (kind, rest) = text.split_once(':').unwrap_or((text, ""));
        let mut given = BTreeMap::new();
        for pair in rest.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let Some((key, value)) = pair.split_once('=') else {
                return Err(SceneError::NotAPair { pair: pair.into() });
            };
            let value = value.trim();
            let value = value.parse::<f64>().map_err(|_| value.to_owned());
            insert(&mut given, key.trim(), Given { value, at: at() })?;
        }
        build(kind.trim(), &at(), given)
    }

    /// The `[scene]` table of the scenario file `path` whose text is `text`; `None` without
    /// one.
    pub fn from_scenario(path: &Path, text: &str) -> Result<Option<Self>, SceneError> {
        #[derive(serde::Deserialize)]
        struct File {
            scene: Option<toml::Spanned<BTreeMap<String, toml::Spanned<toml::Value>>>>,
        }
        let at = |offset: usize| format!("{}:{}", path.display(), line_of(text, offset));
        let file: File = toml::from_str(text).map_err(|e| SceneError::Toml {
            at: at(e.span().map_or(0, |s| s.start)),
            message: e.message().trim().to_owned(),
        })?;
        let Some(table) = file.scene else {
            return Ok(None);
        };
        let table_at = at(table.span().start);
        let mut given = BTreeMap::new();
        let mut kind = None;
        for (key, value) in table.into_inner() {
            let at = at(value.span().start);
            match (key.as_str(), value.into_inner()) {
                ("kind", toml::Value::String(name)) => kind = Some((name, at)),
                ("kind", other) => kind = Some((other.to_string(), at)),
                (_, toml::Value::Float(v)) => insert(&mut given, &key, Given { value: Ok(v), at })?,
                (_, toml::Value::Integer(v)) => {
                    let value = Ok(v as f64);
                    insert(&mut given, &key, Given { value, at })?;
                }
                (_, other) => {
                    let value = Err(other.to_string());
                    insert(&mut given, &key, Given { value, at })?;
                }
            }
        }
        let (kind, kind_at) = kind.ok_or(SceneError::MissingKind { at: table_at })?;
        build(&kind, &kind_at, given).map(Some)
    }
}

/// Adds `key`'s value; a key given twice is refused.
fn insert(given: &mut BTreeMap<String, Given>, key: &str, value: Given) -> Result<(), SceneError> {
    if given.contains_key(key) {
        return Err(SceneError::DuplicateKey {
            at: value.at,
            key: key.into(),
        });
    }
    given.insert(key.into(), value);
    Ok(())
}

/// The 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.get(..offset)
        .map_or(1, |s| s.matches('\n').count() + 1)
}

/// The keys given for a scene, taken one by one.
struct Keys(BTreeMap<String, Given>);

impl Keys {
    /// `key`'s number, `default` if not given; refused outside `low..=high`, or with a
    /// fraction when `whole`.
    fn take(
        &mut self,
        key: &str,
        default: f64,
        [low, high]: [f64; 2],
        whole: bool,
    ) -> Result<f64, SceneError> {
        let Some(g) = self.0.remove(key) else {
            return Ok(default);
        };
        let not_a_number = |value: String| SceneError::NotANumber {
            at: g.at.clone(),
            key: key.to_owned(),
            value,
            expected: if whole {
                "give a whole number"
            } else {
                "give a number"
            },
        };
        let value = g.value.map_err(not_a_number)?;
        if !value.is_finite() || (whole && value.fract() != 0.0) {
            return Err(not_a_number(value.to_string()));
        }
        if !(low..=high).contains(&value) {
            return Err(SceneError::OutOfRange {
                at: g.at,
                key: key.to_owned(),
                value,
                low,
                high,
            });
        }
        Ok(value)
    }

    /// `side`: `ahead` (the default) or `behind`; whether it is behind.
    fn behind(&mut self) -> Result<bool, SceneError> {
        let Some(g) = self.0.remove("side") else {
            return Ok(false);
        };
        let text = match g.value {
            Ok(number) => number.to_string(),
            Err(text) => text,
        };
        match text.trim_matches('"') {
            "ahead" => Ok(false),
            "behind" => Ok(true),
            _ => Err(SceneError::NotANumber {
                at: g.at,
                key: "side".to_owned(),
                value: text,
                expected: "give ahead or behind",
            }),
        }
    }

    /// `key`'s number as [`Keys::take`], not whole.
    fn number(&mut self, key: &str, default: f64, range: [f64; 2]) -> Result<f64, SceneError> {
        self.take(key, default, range, false)
    }
}

/// The scene `kind` with the keys `given`, each checked against its range.
fn build(kind: &str, at: &str, given: BTreeMap<String, Given>) -> Result<Scene, SceneError> {
    let mut keys = Keys(given);
    let (scene, known) = match kind {
        "flat" => (Scene::Flat, "none"),
        "step" => {
            let d = Step::DEFAULT;
            let step = Step {
                height_m: keys.number("height_m", d.height_m, [0.005, 0.3])?,
                riser_x_m: keys.number("riser_x_m", d.riser_x_m, [0.4, 50.0])?,
                depth_m: keys.number("depth_m", d.depth_m, [0.1, 50.0])?,
                behind: keys.behind()?,
            };
            (Scene::Step(step), "height_m, riser_x_m, depth_m, side")
        }
        "flight" => {
            let d = Flight::DEFAULT;
            let count = keys.take("count", f64::from(d.count), [1.0, 5.0], true)?;
            let flight = Flight {
                rise_m: keys.number("rise_m", d.rise_m, [0.005, 0.3])?,
                count: count as u32,
                tread_m: keys.number("tread_m", d.tread_m, [0.1, 5.0])?,
                riser_x_m: keys.number("riser_x_m", d.riser_x_m, [0.4, 50.0])?,
                top_depth_m: keys.number("top_depth_m", d.top_depth_m, [0.1, 50.0])?,
                behind: keys.behind()?,
            };
            let known = "rise_m, count, tread_m, riser_x_m, top_depth_m, side";
            (Scene::Flight(flight), known)
        }
        "ramp" => {
            let d = Ramp::DEFAULT;
            let ramp = Ramp {
                angle_deg: keys.number("angle_deg", d.angle_deg, [0.5, 30.0])?,
                start_x_m: keys.number("start_x_m", d.start_x_m, [0.4, 50.0])?,
                length_m: keys.number("length_m", d.length_m, [0.1, 10.0])?,
                top_depth_m: keys.number("top_depth_m", d.top_depth_m, [0.1, 50.0])?,
                behind: keys.behind()?,
            };
            (
                Scene::Ramp(ramp),
                "angle_deg, start_x_m, length_m, top_depth_m, side",
            )
        }
        "course" => {
            let d = Course::DEFAULT;
            let course = Course {
                step_height_m: keys.number("step_height_m", d.step_height_m, [0.005, 0.3])?,
                ramp_angle_deg: keys.number("ramp_angle_deg", d.ramp_angle_deg, [0.5, 30.0])?,
                behind: keys.behind()?,
            };
            (Scene::Course(course), "step_height_m, ramp_angle_deg, side")
        }
        other => {
            return Err(SceneError::UnknownKind {
                at: at.to_owned(),
                kind: other.to_owned(),
            })
        }
    };
    if let Some((key, g)) = keys.0.into_iter().next() {
        return Err(SceneError::UnknownKey {
            at: g.at,
            kind: scene.kind(),
            key,
            known,
        });
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_line_and_a_scenario_give_the_same_scene() {
        let arg = Scene::from_arg("step:height_m=0.08, riser_x_m=1.5").unwrap();
        let file = "duration_s = 5\n[scene]\nkind = \"step\"\nheight_m = 0.08\nriser_x_m = 1.5\n";
        let toml = Scene::from_scenario(Path::new("s.toml"), file).unwrap();
        assert_eq!(Some(arg), toml);
        let Scene::Step(step) = arg else {
            panic!("{arg:?}")
        };
        assert_eq!((step.height_m, step.depth_m), (0.08, Step::DEFAULT.depth_m));
        assert_eq!(Scene::from_arg("flat").unwrap(), Scene::Flat);
        assert_eq!(
            Scene::from_scenario(Path::new("s.toml"), "duration_s = 5\n").unwrap(),
            None
        );
        let arg = Scene::from_arg("course:side=behind").unwrap();
        let file = "duration_s = 5\n[scene]\nkind = \"course\"\nside = \"behind\"\n";
        let toml = Scene::from_scenario(Path::new("s.toml"), file).unwrap();
        assert_eq!(Some(arg), toml);
        assert!(matches!(arg, Scene::Course(c) if c.behind));
    }

    #[test]
    fn refusals_name_where_and_what() {
        let cases = [
            ("stairs", "--scene: unknown scene `stairs`"),
            ("step:height=0.1", "has no `height`: its keys are height_m"),
            (
                "step:height_m=0.5",
                "height_m = 0.5: give a number from 0.005 to 0.3",
            ),
            ("ramp:angle_deg=steep", "angle_deg = steep"),
            ("flight:count", "write KEY=VALUE"),
            ("flight:count=2.5", "count = 2.5: give a whole number"),
            ("flight:count=9", "count = 9: give a number from 1 to 5"),
            (
                "step:height_m=0.08,height_m=0.1",
                "`height_m` is given twice",
            ),
            ("step:height_m=nan", "height_m = NaN: give a number"),
            ("step:depth_m=inf", "depth_m = inf: give a number"),
            ("step:side=left", "side = left: give ahead or behind"),
        ];
        for (arg, needle) in cases {
            let err = Scene::from_arg(arg).unwrap_err().to_string();
            assert!(err.contains(needle), "{arg}: {err}");
        }
        let file = "duration_s = 5\n\n[scene]\nkind = \"ramp\"\nangle_deg = 45\n";
        let err = Scene::from_scenario(Path::new("s.toml"), file).unwrap_err();
        assert!(
            err.to_string().starts_with("s.toml:5: angle_deg = 45"),
            "{err}"
        );
        let file = "duration_s = 5\n[scene]\nheight_m = 0.1\n";
        let err = Scene::from_scenario(Path::new("s.toml"), file).unwrap_err();
        assert!(
            err.to_string().starts_with("s.toml:2: [scene] needs kind"),
            "{err}"
        );
        let file = "duration_s = 5\n[scene]\nkind = \"step\"\nheight_m = \"0.08\"\n";
        let err = Scene::from_scenario(Path::new("s.toml"), file).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("s.toml:4: height_m = \"0.08\": give a number"),
            "{err}"
        );
    }
}
