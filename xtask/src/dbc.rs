//! `cargo xtask dbc [--check [FILE]]`: writes `protocol/hybrid_robot.dbc` from the protocol
//! crate's message definitions; `--check` fails when the committed file (or FILE, a DBC someone
//! hands you) differs from what they produce, naming the file and the first line that differs.

use std::path::{Path, PathBuf};

use crate::util::root;

pub fn run(args: &[String]) -> Result<(), String> {
    let committed = root().join("protocol").join("hybrid_robot.dbc");
    let check = match args {
        [] => None,
        [flag] if flag == "--check" => Some(committed.clone()),
        [flag, file] if flag == "--check" => Some(PathBuf::from(file)),
        _ => return Err("usage: cargo xtask dbc [--check [FILE]]".into()),
    };
    let mut text = String::new();
    protocol::dbc::write_dbc(&mut text).map_err(|_| "formatting the DBC failed".to_string())?;
    if let Some(path) = check {
        return check_file(&path, &text);
    }
    std::fs::write(&committed, text)
        .map_err(|e| format!("cannot write {}: {e}", committed.display()))?;
    eprintln!("dbc: wrote {}", committed.display());
    Ok(())
}

fn check_file(path: &Path, generated: &str) -> Result<(), String> {
    let found = std::fs::read(path).map_err(|e| {
        format!(
            "{}: cannot read the DBC ({e}); run `cargo xtask dbc` to write it",
            path.display()
        )
    })?;
    let found = String::from_utf8(found).map_err(|e| {
        let line = 1 + e.as_bytes()[..e.utf8_error().valid_up_to()]
            .iter()
            .filter(|b| **b == b'\n')
            .count();
        format!("{}:{line}: not UTF-8 text, not a DBC", path.display())
    })?;
    match first_difference(generated, &found) {
        None => {
            eprintln!("dbc: {} is up to date", path.display());
            Ok(())
        }
        Some((line, expected, got)) => Err(format!(
            "{}:{line}: differs from the protocol's definitions\n  expected: {expected}\n  found:    {got}\n\
             The message definitions changed or the file was edited by hand: run `cargo xtask dbc` and commit the result.",
            path.display()
        )),
    }
}

/// The first line (1-based) where `found` differs from `expected`, with both lines (an empty
/// string where one file has ended).
fn first_difference<'a>(expected: &'a str, found: &'a str) -> Option<(usize, &'a str, &'a str)> {
    let mut want = expected.lines();
    let mut got = found.lines();
    for line in 1.. {
        match (want.next(), got.next()) {
            (None, None) => {
                return (expected.ends_with('\n') != found.ends_with('\n')).then_some((
                    line,
                    "(end of file)",
                    "(end of file)",
                ))
            }
            (a, b) if a == b => {}
            (a, b) => {
                return Some((
                    line,
                    a.unwrap_or("(end of file)"),
                    b.unwrap_or("(end of file)"),
                ))
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_first_differing_line() {
        let generated = "VERSION \"\"\n\nBU_: A B\nBO_ 1 X: 8 A\n";
        assert_eq!(first_difference(generated, generated), None);
        let edited = "VERSION \"\"\n\nBU_: A B\nBO_ 1 X: 9 A\n";
        assert_eq!(
            first_difference(generated, edited),
            Some((4, "BO_ 1 X: 8 A", "BO_ 1 X: 9 A"))
        );
        assert_eq!(
            first_difference(generated, "VERSION \"\"\n"),
            Some((2, "", "(end of file)"))
        );
    }

    #[test]
    fn a_malformed_file_is_reported_with_its_path_and_line() {
        let dir = std::env::temp_dir().join(format!("xtask-dbc-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("broken.dbc");
        std::fs::write(&path, "VERSION \"\"\n\nBU_: A B\nBO_ garbage\n").unwrap();
        let mut generated = String::new();
        protocol::dbc::write_dbc(&mut generated).unwrap();
        let error = check_file(&path, &generated).unwrap_err();
        assert!(
            error.starts_with(&format!("{}:", path.display())),
            "{error}"
        );
        let missing = check_file(&dir.join("missing.dbc"), &generated).unwrap_err();
        assert!(missing.contains("missing.dbc: cannot read"), "{missing}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
