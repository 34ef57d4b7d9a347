//! `sim-host export`: a run's text logs from its `run.mcap`.

use std::path::PathBuf;

use clap::Args;
use sim_host::output::export::{export, ExportError, ExportTargets};

/// What to export, and where.
#[derive(Debug, Args)]
pub(crate) struct ExportArgs {
    /// The run's MCAP (`run.mcap` in its output folder).
    pub(crate) mcap: PathBuf,
    /// Folder for bus.log (candump `-L`) and telemetry.csv (default: the MCAP's folder).
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// The SocketCAN interface the candump lines name (canplayer replays on it).
    #[arg(long, default_value = "vcan0")]
    pub(crate) bus: String,
    /// Replace bus.log and telemetry.csv where they exist (a run's own, or an earlier export).
    #[arg(long)]
    pub(crate) force: bool,
}

/// Exports and prints what was written; a file cut short is exported up to the cut and
/// reported as an error.
pub(crate) fn run(args: &ExportArgs) -> Result<(), String> {
    let dir = args.out.clone().unwrap_or_else(|| {
        args.mcap
            .parent()
            .map_or_else(|| PathBuf::from("."), PathBuf::from)
    });
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let targets = ExportTargets {
        candump: Some((dir.join("bus.log"), args.bus.clone())),
        csv: Some(dir.join("telemetry.csv")),
    };
    let candump = targets.candump.iter().map(|(path, _)| path);
    if let Some(taken) = candump.chain(&targets.csv).find(|path| path.exists()) {
        if !args.force {
            return Err(format!(
                "{} exists (the run's own log, or an earlier export): give another folder with --out, or --force to replace it",
                taken.display()
            ));
        }
    }
    let result = export(&args.mcap, &targets);
    let exported = match &result {
        Ok(exported) | Err(ExportError::CutShort { exported, .. }) => Some(*exported),
        Err(_) => None,
    };
    if let Some(exported) = exported {
        println!(
            "exported         {} frames, {} rows, up to {:.3} s",
            exported.frames, exported.rows, exported.last_time_s
        );
        let candump = targets.candump.iter().map(|(path, _)| path);
        for path in candump.chain(&targets.csv) {
            println!("wrote            {}", path.display());
        }
    }
    result.map(|_| ()).map_err(|e| e.to_string())
}
