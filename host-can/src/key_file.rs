//! The bus key as host programs read it: `--key-file PATH`, a file holding the 16-byte key as
//! 32 hexadecimal digits. Real keys live outside the repository, readable by the operator's
//! account only (see `docs/protocol.md`, "Keys"). Without a file the programs use the public
//! test key of simulation and CI, and say so.

use std::path::{Path, PathBuf};

use protocol::{Key, KeyError, TEST_KEY};

/// Why a key file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum KeyFileError {
    /// The file could not be read.
    #[error("key file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
    /// The file does not hold a key.
    #[error("key file {path}: {error}; write the key as one line of 32 hexadecimal digits")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        error: KeyError,
    },
}

/// The key in `path`, or the test key (with a warning in the log) when there is none.
pub fn load(path: Option<&Path>) -> Result<Key, KeyFileError> {
    let Some(path) = path else {
        tracing::warn!(
            "no --key-file: using the public test key of simulation and CI; \
             a robot on this key obeys anyone who reads the repository"
        );
        return Ok(TEST_KEY);
    };
    let text = std::fs::read_to_string(path).map_err(|source| KeyFileError::Io {
        path: path.to_owned(),
        source,
    })?;
    Key::from_hex(&text).map_err(|error| KeyFileError::Format {
        path: path.to_owned(),
        error,
    })
}
