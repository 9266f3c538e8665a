//! Ctrl+C or `kill` during a render or its write: real signals at many moments, never a
//! temporary file left, and the file already at the destination left as it was.
//!
//! Each signal is sent at a known moment, not after a sleep that may land anywhere: only once
//! the process catches SIGINT and SIGTERM (its `SigCgt` mask in `/proc`, which Linux has), and,
//! to stop a write in progress, while the write waits in the test hook `RAYLAB_TEST_PAUSE_WRITE`
//! (the image's bytes in the temporary file, not yet renamed: `film::write_atomically_with`),
//! which makes a file to say it is there. The hook is set in every run, so none can finish on
//! its own and every run must end by the signal (exit 130).
#![cfg(target_os = "linux")]

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const TIMEOUT: Duration = Duration::from_secs(60);

/// The file at the destination before each run: not an image, and never read by the render.
const OLD: &[u8] = b"the student's earlier render";

fn start_render(out: &Path, samples: u32, pause_sign: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(["render", "--width", "1200", "--height", "1200", "--samples"])
        .arg(samples.to_string())
        .arg("--out")
        .arg(out)
        .env("RAYLAB_TEST_PAUSE_WRITE", pause_sign)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until the process catches SIGINT and SIGTERM: bits 1 and 14 (signal − 1) of the
/// `SigCgt` mask Linux shows in `/proc/PID/status`.
fn wait_for_handlers(child: &mut Child) {
    let status = format!("/proc/{}/status", child.id());
    let wanted = (1u64 << 1) | (1u64 << 14);
    let start = Instant::now();
    loop {
        let text = std::fs::read_to_string(&status).unwrap();
        let caught = text
            .lines()
            .find_map(|l| l.strip_prefix("SigCgt:"))
            .map(|mask| u64::from_str_radix(mask.trim(), 16).unwrap())
            .expect("a SigCgt line");
        if caught & wanted == wanted {
            return;
        }
        assert!(
            child.try_wait().unwrap().is_none(),
            "ended before catching signals"
        );
        assert!(start.elapsed() < TIMEOUT, "no handlers within {TIMEOUT:?}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Waits for `sign` to exist (the write paused in the hook), the render still running.
fn wait_for(sign: &Path, child: &mut Child) {
    let start = Instant::now();
    while !sign.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "ended before its write paused"
        );
        assert!(start.elapsed() < TIMEOUT, "no write within {TIMEOUT:?}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn temporary_files(dir: &Path) -> Vec<(String, u64)> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .map(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            (name, e.metadata().unwrap().len())
        })
        .collect()
}

#[test]
fn an_interrupted_render_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let signs = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.exr");
    for (i, signal) in ["INT", "TERM"].iter().cycle().take(8).enumerate() {
        std::fs::write(&out, OLD).unwrap();
        let sign = signs.path().join(format!("paused-{i}"));
        let during_write = i % 2 == 1;
        let samples = if during_write { 1 } else { 64 };
        let mut child = start_render(&out, samples, &sign);
        wait_for_handlers(&mut child);
        if during_write {
            // The write has begun: its temporary file holds the image, not yet renamed.
            wait_for(&sign, &mut child);
            let tmp = temporary_files(dir.path());
            assert!(
                tmp.len() == 1 && tmp[0].1 > 0,
                "step {i}: paused in the write, but the temporary files are {tmp:?}"
            );
        } else {
            // During the render, at a different moment each time: 64 samples of 1200²
            // take far longer than the last of these sleeps.
            std::thread::sleep(Duration::from_millis(40 * i as u64));
            assert!(
                !sign.exists() && temporary_files(dir.path()).is_empty(),
                "step {i}: the render reached its write before the signal"
            );
        }
        let killed = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status()
            .unwrap();
        assert!(killed.success());
        let start = Instant::now();
        let output = loop {
            if child.try_wait().unwrap().is_some() {
                break child.wait_with_output().unwrap();
            }
            assert!(start.elapsed() < TIMEOUT, "did not stop");
            std::thread::sleep(Duration::from_millis(5));
        };
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            output.status.code(),
            Some(130),
            "SIG{signal} at step {i}: {stderr}"
        );
        assert!(stderr.contains("interrupted"), "{stderr}");
        if !during_write {
            assert!(!sign.exists(), "step {i}: the write began after all");
        }
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["big.exr"], "after SIG{signal} at step {i}");
        assert_eq!(
            std::fs::read(&out).unwrap(),
            OLD,
            "step {i}: the old file was changed"
        );
    }
}
