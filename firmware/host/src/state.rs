//! What firmware-host keeps across restarts, as the MCU keeps it in a backup register: the
//! last session epoch it opened (every start opens a greater one, so that no frame recorded in
//! an earlier session is fresh in this one) and whether an E-stop is latched (a latched E-stop
//! survives a restart; only a fresh, authenticated release clears it).
//!
//! The file is two lines of TOML, written whole to a temporary file and renamed over the old
//! one, so that a crash leaves the old state or the new, never half of one.

use std::fs;
use std::path::{Path, PathBuf};

use protocol::Epoch;
use serde::{Deserialize, Serialize};

/// Why the state file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    /// Reading or writing failed.
    #[error("state file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// The file is not the state this program writes.
    #[error(
        "state file {path}: {message}. It holds `epoch = N` and `estop_latched = true|false`; \
         fix it, or move it away and start with `--epoch` above the last epoch the controller \
         announced (candump shows it in frames on id 020)"
    )]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, with its line.
        message: String,
    },
    /// Every epoch has been used.
    #[error(
        "state file {path}: epoch {last} is the last there is; this controller needs a new key"
    )]
    Exhausted {
        /// The file.
        path: PathBuf,
        /// The last epoch.
        last: u32,
    },
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
struct Contents {
    epoch: u32,
    estop_latched: bool,
}

/// The state file of one controller.
#[derive(Debug)]
pub struct StateFile {
    path: PathBuf,
    contents: Contents,
}

impl StateFile {
    /// Opens (or starts) the state at `path` and takes the next epoch, at least `at_least`:
    /// the file is written with it before anything is sent. Returns the state, the epoch of
    /// this start, and whether an E-stop was latched when the last run ended.
    pub fn start(
        path: &Path,
        at_least: Option<Epoch>,
    ) -> Result<(StateFile, Epoch, bool), StateError> {
        let previous = match fs::read_to_string(path) {
            Ok(text) => Some(
                toml::from_str::<Contents>(&text).map_err(|e| StateError::Parse {
                    path: path.to_owned(),
                    message: e.message().to_owned() + &line_of(&text, e.span()),
                })?,
            ),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
            Err(source) => {
                return Err(StateError::Io {
                    path: path.to_owned(),
                    source,
                })
            }
        };
        let last = previous.map_or(0, |c| c.epoch);
        let next = last.checked_add(1).ok_or(StateError::Exhausted {
            path: path.to_owned(),
            last,
        })?;
        let epoch = next.max(at_least.map_or(0, Epoch::raw));
        let latched = previous.is_some_and(|c| c.estop_latched);
        let mut state = StateFile {
            path: path.to_owned(),
            contents: Contents {
                epoch,
                estop_latched: latched,
            },
        };
        state.write()?;
        Ok((state, Epoch::new(epoch), latched))
    }

    /// Records whether the E-stop is latched (written at once when it changes).
    pub fn record_latch(&mut self, latched: bool) -> Result<(), StateError> {
        if self.contents.estop_latched == latched {
            return Ok(());
        }
        self.contents.estop_latched = latched;
        self.write()
    }

    fn write(&mut self) -> Result<(), StateError> {
        let io = |source| StateError::Io {
            path: self.path.clone(),
            source,
        };
        let text = toml::to_string(&self.contents).map_err(|e| StateError::Parse {
            path: self.path.clone(),
            message: e.to_string(),
        })?;
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::create_dir_all(dir).map_err(io)?;
        }
        // Written, synced, renamed over the old file, and the directory synced: after a power
        // loss the file holds the old state or the new one, never a rolled-back epoch.
        let temporary = self.path.with_extension("tmp");
        let mut file = fs::File::create(&temporary).map_err(io)?;
        std::io::Write::write_all(&mut file, text.as_bytes()).map_err(io)?;
        file.sync_all().map_err(io)?;
        fs::rename(&temporary, &self.path).map_err(io)?;
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            fs::File::open(dir).and_then(|d| d.sync_all()).map_err(io)?;
        }
        Ok(())
    }
}

fn line_of(text: &str, span: Option<std::ops::Range<usize>>) -> String {
    span.map(|span| {
        let line = text
            .get(..span.start)
            .map_or(0, |t| t.matches('\n').count())
            + 1;
        format!(" (line {line})")
    })
    .unwrap_or_default()
}

/// Where the state lives when no `--state-file` is given: `$XDG_STATE_HOME/hybrid-robot/`, or
/// `~/.local/state/hybrid-robot/`; `None` when neither variable is set.
pub fn default_path() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_STATE_HOME")
        .map(PathBuf::from)
        .or_else(|| {
            std::env::var_os("HOME").map(|home| PathBuf::from(home).join(".local/state"))
        })?;
    Some(base.join("hybrid-robot").join("firmware-host.toml"))
}
