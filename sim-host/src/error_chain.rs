//! Error messages with their causes: mujoco-rs's own messages are terse and put the detail in
//! the source.

use std::error::Error;

/// `error` and its sources, `: `-separated.
pub fn chain(error: &dyn Error) -> String {
    let mut text = error.to_string();
    let mut next = error.source();
    while let Some(cause) = next {
        text.push_str(": ");
        text.push_str(&cause.to_string());
        next = cause.source();
    }
    text
}
