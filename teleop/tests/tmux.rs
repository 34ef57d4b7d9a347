//! End to end: the interactive program in a real terminal (tmux), driven by keys against the
//! simulated robot (`teleop --bus inproc`, what `cargo xtask demo --teleop` runs), checked on
//! the screen and in the telemetry it leaves.
#![cfg(feature = "sim")]

use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};

/// A tmux session, killed when dropped.
struct Tmux {
    name: String,
}

impl Tmux {
    fn start(command: &str) -> Self {
        let name = format!("teleop-test-{}", std::process::id());
        let status = Command::new("tmux")
            .args(["new-session", "-d", "-s", &name, "-x", "120", "-y", "45", command])
            .status()
            .unwrap_or_else(|e| {
                panic!("tmux did not start ({e}): install it (apt-get install tmux; `cargo xtask setup` does)")
            });
        assert!(status.success(), "tmux new-session failed");
        Self { name }
    }

    fn keys(&self, keys: &str) {
        let status = Command::new("tmux")
            .args(["send-keys", "-t", &self.name, keys])
            .status()
            .unwrap();
        assert!(status.success());
    }

    fn screen(&self) -> String {
        let out = Command::new("tmux")
            .args(["capture-pane", "-p", "-S", "-60", "-t", &self.name])
            .output()
            .unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    /// Waits until `check` accepts the screen; panics with the screen after `limit`.
    fn wait(&self, what: &str, limit: Duration, check: impl Fn(&str) -> bool) -> String {
        let until = Instant::now() + limit;
        loop {
            let screen = self.screen();
            if check(&screen) {
                return screen;
            }
            assert!(
                Instant::now() < until,
                "waited {limit:?} for {what}; the screen:\n{screen}"
            );
            std::thread::sleep(Duration::from_millis(200));
        }
    }
}

impl Drop for Tmux {
    fn drop(&mut self) {
        let _ = Command::new("tmux")
            .args(["kill-session", "-t", &self.name])
            .status();
    }
}

/// The simulator panel's x, m.
fn sim_x(screen: &str) -> Option<f64> {
    let line = screen.lines().find(|l| l.contains(" s   x "))?;
    let after = line.split("   x ").nth(1)?;
    after.split_whitespace().next()?.parse().ok()
}

#[test]
fn an_operator_drives_the_simulated_robot_from_the_terminal() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("tmux-teleop");
    let _ = std::fs::remove_dir_all(&out);
    let command = format!(
        "{} --bus inproc --out {}; echo TELEOP-EXIT $?; sleep 120",
        env!("CARGO_BIN_EXE_teleop"),
        out.display()
    );
    let tmux = Tmux::start(&command);
    tmux.wait("the controller's status", Duration::from_secs(30), |s| {
        s.contains("mode   Stop") && sim_x(s).is_some()
    });

    tmux.keys("w");
    let screen = tmux.wait("the robot to drive 1 m", Duration::from_secs(40), |s| {
        sim_x(s).is_some_and(|x| x >= 1.0)
    });
    assert!(screen.contains("command W wheels forward"), "{screen}");
    assert!(screen.contains("mode   WheelForward"), "{screen}");
    assert!(!screen.contains("SILENT"), "{screen}");

    tmux.keys("Space");
    tmux.wait("the E-stop", Duration::from_secs(5), |s| {
        s.contains("E-STOP LATCHED") && s.contains("mode   EStop")
    });

    tmux.keys("q");
    let screen = tmux.wait("teleop to exit", Duration::from_secs(30), |s| {
        s.contains("TELEOP-EXIT")
    });
    assert!(screen.contains("TELEOP-EXIT 0"), "{screen}");
    assert!(screen.contains("the robot was told to stop"), "{screen}");

    // The telemetry agrees: the torso went forward at least 1 m.
    let csv = std::fs::read_to_string(out.join("telemetry.csv")).unwrap();
    let mut rows = csv.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let x_col = header
        .iter()
        .position(|h| h.starts_with("torso_x"))
        .unwrap();
    let last = rows.last().unwrap();
    let x: f64 = last.split(',').nth(x_col).unwrap().parse().unwrap();
    println!("MEASURED tmux drive: the torso ended at x = {x:.2} m");
    assert!(x >= 1.0, "{x}");
}
