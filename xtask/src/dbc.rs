//! `cargo xtask dbc [--check]`: writes `protocol/hybrid_robot.dbc` from the protocol crate's
//! message definitions; `--check` fails when the committed file differs from what they produce.

use crate::util::root;

pub fn run(args: &[String]) -> Result<(), String> {
    let check = match args {
        [] => false,
        [flag] if flag == "--check" => true,
        _ => return Err("usage: cargo xtask dbc [--check]".into()),
    };
    let mut text = String::new();
    protocol::dbc::write_dbc(&mut text).map_err(|_| "formatting the DBC failed".to_string())?;
    let path = root().join("protocol").join("hybrid_robot.dbc");
    if check {
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        if committed != text {
            return Err(format!(
                "{} is stale: the message definitions changed. Run `cargo xtask dbc` and commit the result.",
                path.display()
            ));
        }
        eprintln!("dbc: {} is up to date", path.display());
        return Ok(());
    }
    std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    eprintln!("dbc: wrote {}", path.display());
    Ok(())
}
