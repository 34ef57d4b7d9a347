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
    /// A value that is not a number, or outside its range.
    #[error("{at}: {key} = {value}: {allowed}")]
    Value {
        /// Where it was given.
        at: String,
        /// The key.
        key: String,
        /// The value as given.
        value: String,
        /// What is allowed.
        allowed: String,
    },
    /// Text that is not `KIND` or `KIND:KEY=VALUE,…`, or a `[scene]` table without `kind`.
    #[error("{at}: {message}")]
    Syntax {
        /// Where it was given.
        at: String,
        /// What is wrong and how to write it.
        message: String,
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

/// One key's value and where it was given.
struct Given {
    value: String,
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
                return Err(SceneError::Syntax {
                    at: at(),
                    message: format!("`{pair}`: write KEY=VALUE, e.g. step:height_m=0.08"),
                });
            };
            let value = value.trim().to_owned();
            given.insert(key.trim().to_owned(), Given { value, at: at() });
        }
        build(kind.trim(), &at(), given)
    }

    /// The `[scene]` table of the scenario file `path` whose text is `text`; `None` without
    /// one.
    pub fn from_scenario(path: &Path, text: &str) -> Result<Option<Self>, SceneError> {
        #[derive(serde::Deserialize)]
        struct File {
            scene: Option<BTreeMap<String, toml::Spanned<toml::Value>>>,
        }
        let at = |offset: usize| format!("{}:{}", path.display(), line_of(text, offset));
        let file: File = toml::from_str(text).map_err(|e| SceneError::Syntax {
            at: at(e.span().map_or(0, |s| s.start)),
            message: e.message().trim().to_owned(),
        })?;
        let Some(table) = file.scene else {
            return Ok(None);
        };
        let mut given = BTreeMap::new();
        for (key, value) in table {
            let shown = match value.get_ref() {
                toml::Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            let at = at(value.span().start);
            given.insert(key, Given { value: shown, at });
        }
        let Some(kind) = given.remove("kind") else {
            return Err(SceneError::Syntax {
                at: format!("{}", path.display()),
                message:
                    "[scene] needs kind = \"flat\", \"step\", \"flight\", \"ramp\" or \"course\""
                        .into(),
            });
        };
        build(&kind.value, &kind.at, given).map(Some)
    }
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
        match g.value.parse::<f64>() {
            Ok(v) if v.is_finite() && (low..=high).contains(&v) && !(whole && v.fract() != 0.0) => {
                Ok(v)
            }
            _ => Err(SceneError::Value {
                at: g.at,
                key: key.to_owned(),
                value: g.value,
                allowed: if whole {
                    format!("give a whole number from {low} to {high}")
                } else {
                    format!("give a number from {low} to {high}")
                },
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
            };
            (Scene::Step(step), "height_m, riser_x_m, depth_m")
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
            };
            let known = "rise_m, count, tread_m, riser_x_m, top_depth_m";
            (Scene::Flight(flight), known)
        }
        "ramp" => {
            let d = Ramp::DEFAULT;
            let ramp = Ramp {
                angle_deg: keys.number("angle_deg", d.angle_deg, [0.5, 30.0])?,
                start_x_m: keys.number("start_x_m", d.start_x_m, [0.4, 50.0])?,
                length_m: keys.number("length_m", d.length_m, [0.1, 10.0])?,
                top_depth_m: keys.number("top_depth_m", d.top_depth_m, [0.1, 50.0])?,
            };
            (
                Scene::Ramp(ramp),
                "angle_deg, start_x_m, length_m, top_depth_m",
            )
        }
        "course" => {
            let d = Course::DEFAULT;
            let course = Course {
                step_height_m: keys.number("step_height_m", d.step_height_m, [0.005, 0.3])?,
                ramp_angle_deg: keys.number("ramp_angle_deg", d.ramp_angle_deg, [0.5, 30.0])?,
            };
            (Scene::Course(course), "step_height_m, ramp_angle_deg")
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
            (
                "flight:count=2.5",
                "count = 2.5: give a whole number from 1 to 5",
            ),
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
        assert!(err.to_string().contains("needs kind"), "{err}");
    }
}
