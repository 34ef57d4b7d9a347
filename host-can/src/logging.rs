//! Logging for the host programs (firmware-host, sim-host, teleop): `tracing` to stderr, the
//! level from `RUST_LOG` when set, so that stdout stays for results a script reads.

/// Starts logging at `default_level` ("info", "warn", …) unless `RUST_LOG` says otherwise.
pub fn init(default_level: &str) {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default_level)),
        )
        .with_writer(std::io::stderr)
        .init();
}
