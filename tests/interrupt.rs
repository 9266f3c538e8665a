//! Ctrl+C or `kill` during a render or its write: real signals at many moments, never a
//! temporary file left, and the destination either absent or a whole image.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

fn start_render(out: &std::path::Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_raylab"))
        .args(["render", "--width", "1200", "--height", "1200", "--out"])
        .arg(out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

#[test]
fn an_interrupted_render_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("big.exr");
    let (mut interrupted, mut mid_write) = (0, 0);
    for (i, signal) in ["INT", "TERM"].iter().cycle().take(12).enumerate() {
        let _ = std::fs::remove_file(&out);
        let mut child = start_render(&out);
        if i % 2 == 0 {
            // During the render: 20 ms after the start (the handler is in place) and later.
            std::thread::sleep(Duration::from_millis(20 + 50 * i as u64));
        } else {
            // During the write: as soon as the temporary file appears. A write that finished
            // between two looks is tried again, so that every such step does kill a write in
            // progress and is counted only then.
            let mut seen = false;
            for _attempt in 0..10 {
                while !has_temporary_file(dir.path()) && child.try_wait().unwrap().is_none() {
                    std::thread::sleep(Duration::from_micros(200));
                }
                if has_temporary_file(dir.path()) {
                    seen = true;
                    break;
                }
                let _ = child.wait();
                let _ = std::fs::remove_file(&out);
                child = start_render(&out);
            }
            assert!(
                seen,
                "step {i}: never saw the temporary file in ten renders"
            );
            mid_write += 1;
        }
        let _ = Command::new("kill")
            .args([&format!("-{signal}"), &child.id().to_string()])
            .status();
        let start = Instant::now();
        let output = loop {
            if child.try_wait().unwrap().is_some() {
                break child.wait_with_output().unwrap();
            }
            assert!(start.elapsed() < Duration::from_secs(60), "did not stop");
            std::thread::sleep(Duration::from_millis(5));
        };
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(
            names
                .iter()
                .all(|n| !n.ends_with(".tmp") && !n.ends_with(".check")),
            "after SIG{signal} at step {i}: {names:?}"
        );
        match output.status.code() {
            Some(130) => {
                interrupted += 1;
                let stderr = String::from_utf8_lossy(&output.stderr);
                assert!(stderr.contains("interrupted"), "{stderr}");
            }
            Some(0) => {}
            other => panic!(
                "exit {other:?}: {}",
                String::from_utf8_lossy(&output.stderr)
            ),
        }
        if out.exists() {
            let image = image::open(&out).expect("a whole image, never a partial one");
            assert_eq!((image.width(), image.height()), (1200, 1200));
        }
    }
    assert!(
        interrupted >= 4,
        "too few runs were interrupted ({interrupted}) to prove much"
    );
    // Six kills were sent while a temporary file existed.
    assert_eq!(mid_write, 6);
}

fn has_temporary_file(dir: &std::path::Path) -> bool {
    std::fs::read_dir(dir)
        .unwrap()
        .any(|e| e.unwrap().file_name().to_string_lossy().ends_with(".tmp"))
}
