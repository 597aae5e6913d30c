//! The user's files are safe: an output that is an input is refused before any work, a
//! symlink stays a link and its target is written, a replaced file keeps its mode, a device or
//! FIFO is written into (not replaced), a read-only file or a missing folder is refused before
//! the work, and an interrupted command leaves no temporary file behind.

use std::io::Read;
use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use isoforge_mesh::{check, read_mesh};

use crate::{fixtures, isoforge, isoforge_bin};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("folder")
        .map(|e| e.expect("entry").file_name().into_string().expect("utf-8"))
        .collect();
    v.sort();
    v
}

/// Copies a fixture into `dir` and returns the copy's path.
fn copy(dir: &Path, fixture: &str) -> PathBuf {
    let from = fixtures().join(fixture);
    let to = dir.join(from.file_name().expect("a file name"));
    std::fs::copy(&from, &to).expect("copy");
    to
}

/// Asserts a run failed with status 1 and a message containing `word`.
fn refused(run: &Output, word: &str, what: &str) {
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{what}: {err}");
    assert!(err.contains(word), "{what}: {err:?} lacks {word:?}");
    assert!(!err.contains("panicked"), "{what}: {err}");
}

/// Waits for a child at most `limit`, killing it and failing if it takes longer.
fn wait_at_most(mut child: Child, limit: Duration, what: &str) -> Output {
    let deadline = Instant::now() + limit;
    while Instant::now() < deadline {
        if child.try_wait().expect("try_wait").is_some() {
            return child.wait_with_output().expect("output");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
    panic!("{what}: still running after {limit:?}: the work started before the check");
}

fn spawn(args: &[&str]) -> Child {
    Command::new(isoforge_bin())
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("isoforge starts")
}

fn kill(child: &Child, signal: &str) {
    let status = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success());
}

#[test]
fn an_output_that_is_an_input_is_refused_and_the_input_kept() {
    let dir = tempfile::tempdir().unwrap();
    let model = copy(dir.path(), "slice/torus.rhai");
    let profile = copy(dir.path(), "printers/generic_marlin_220.toml");
    let resin = copy(dir.path(), "printers/prusa_sl1.toml");
    let gcode = copy(dir.path(), "gcode/square-tube.gcode");
    let before: Vec<(PathBuf, Vec<u8>)> = [&model, &profile, &resin, &gcode]
        .iter()
        .map(|p| (p.to_path_buf(), std::fs::read(p).unwrap()))
        .collect();
    // The same file under another spelling counts too.
    let model_again = dir.path().join(".").join("torus.rhai");
    let (m, m2, p, r, g) = (
        s(&model),
        s(&model_again),
        s(&profile),
        s(&resin),
        s(&gcode),
    );
    let cases: Vec<Vec<&str>> = vec![
        vec!["mesh", m, "-o", m2, "--depth", "4"],
        vec!["mesh", m, "-o", m, "--format", "stl"],
        vec!["slice", m, "--profile", p, "-o", m],
        vec!["slice", m, "--profile", p, "-o", p],
        vec!["slice", m, "--profile", r, "--sl1", m],
        vec!["slice", m, "--profile", r, "--svx", r],
        vec!["render", m, "-o", m, "--size", "8x8"],
        vec![
            "print",
            g,
            "--journal",
            g,
            "--port",
            "/dev/isoforge-no-such-port",
        ],
    ];
    for args in &cases {
        refused(&isoforge(args), "input", &args.join(" "));
    }
    // The fake printer has no input; it refuses to replace a file that is not its log.
    let run = isoforge(&["fake-printer", "--log", g]);
    refused(
        &run,
        "not a fake-printer log",
        "fake-printer --log FILE.gcode",
    );
    assert!(run.stdout.is_empty(), "no printer was started");
    for (path, bytes) in &before {
        assert_eq!(&std::fs::read(path).unwrap(), bytes, "{}", path.display());
    }
    assert_eq!(
        names(dir.path()),
        [
            "generic_marlin_220.toml",
            "prusa_sl1.toml",
            "square-tube.gcode",
            "torus.rhai"
        ],
        "nothing else written, no temporary left"
    );
}

#[test]
fn a_symlink_stays_a_link_and_its_target_gets_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("real");
    std::fs::create_dir(&real).unwrap();
    let target = real.join("sphere.stl");
    std::fs::write(&target, b"old").unwrap();
    let link = dir.path().join("link.stl");
    std::os::unix::fs::symlink("real/sphere.stl", &link).unwrap();
    let sphere = fixtures().join("bench/sphere.rhai");
    let run = isoforge(&["mesh", s(&sphere), "-o", s(&link), "--depth", "4"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let meta = std::fs::symlink_metadata(&link).unwrap();
    assert!(meta.file_type().is_symlink(), "the link is still a link");
    let mesh = read_mesh(&target).expect("the target holds the mesh");
    assert!(check(&mesh).is_closed_manifold());
    assert_eq!(names(&real), ["sphere.stl"]);
    assert_eq!(names(dir.path()), ["link.stl", "real"]);
}

#[test]
fn a_replaced_file_keeps_its_mode_and_a_read_only_one_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let heart = fixtures().join("classic/heart.rhai");
    let out = dir.path().join("heart.png");
    std::fs::write(&out, b"old").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
    let run = isoforge(&["render", s(&heart), "-o", s(&out), "--size", "16x12"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let meta = std::fs::metadata(&out).unwrap();
    assert_eq!(meta.permissions().mode() & 0o7777, 0o640);
    assert_eq!(&std::fs::read(&out).unwrap()[1..4], b"PNG");

    let ro = dir.path().join("ro.stl");
    std::fs::write(&ro, b"keep").unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o444)).unwrap();
    let run = isoforge(&["mesh", s(&heart), "-o", s(&ro), "--depth", "4"]);
    refused(&run, "read-only", "mesh -o read-only file");
    assert_eq!(std::fs::read(&ro).unwrap(), b"keep");
    assert_eq!(names(dir.path()), ["heart.png", "ro.stl"]);
}

#[test]
fn devices_and_fifos_are_written_into_not_replaced() {
    let heart = fixtures().join("classic/heart.rhai");
    // /dev/full fails every write: the command says so, and the device stays a device.
    let run = isoforge(&["render", s(&heart), "-o", "/dev/full", "--size", "8x8"]);
    refused(&run, "/dev/full", "render -o /dev/full");
    let full = std::fs::metadata("/dev/full").unwrap();
    assert!(full.file_type().is_char_device());
    // A FIFO gets the mesh through it.
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.stl");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_end(&mut bytes)
                .unwrap();
            bytes
        })
    };
    let run = isoforge(&["mesh", s(&heart), "-o", s(&fifo), "--depth", "4"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let bytes = reader.join().unwrap();
    let triangles = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
    assert!(triangles > 0);
    assert_eq!(bytes.len(), 84 + 50 * triangles, "a whole binary STL");
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(names(dir.path()), ["pipe.stl"]);
}

#[test]
fn a_missing_output_folder_is_refused_before_the_work() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no/such/folder");
    // Meshing this at depth 10 takes over half a minute in a debug build; refusing takes
    // as long as loading the script.
    let gyroid = fixtures().join("bench/gyroid_sphere.rhai");
    let out = missing.join("gyroid.stl");
    let child = spawn(&["mesh", s(&gyroid), "-o", s(&out), "--depth", "10"]);
    let run = wait_at_most(child, Duration::from_secs(20), "mesh into a missing folder");
    refused(&run, "does not exist", "mesh into a missing folder");
    assert!(String::from_utf8_lossy(&run.stderr).contains("no/such/folder"));
    // Slicing 0.01 mm layers would take long too.
    let torus = fixtures().join("slice/torus.rhai");
    let out = missing.join("torus.sl1");
    let child = spawn(&[
        "slice",
        s(&torus),
        "--profile",
        s(&fixtures().join("printers/prusa_sl1.toml")),
        "--set",
        "layer_height=0.01",
        "--sl1",
        s(&out),
    ]);
    let run = wait_at_most(
        child,
        Duration::from_secs(20),
        "slice into a missing folder",
    );
    refused(&run, "does not exist", "slice into a missing folder");
    assert!(names(dir.path()).is_empty());
}

#[test]
fn a_terminated_mesh_leaves_no_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let model = copy(dir.path(), "bench/gyroid_sphere.rhai");
    let out = dir.path().join("gyroid.stl");
    let child = spawn(&["mesh", s(&model), "-o", s(&out), "--depth", "10"]);
    // The temporary appears when the output is prepared, just before meshing starts.
    let deadline = Instant::now() + Duration::from_secs(30);
    let temp = loop {
        let found = names(dir.path())
            .into_iter()
            .find(|n| n.starts_with(".isoforge-") && n.ends_with(".tmp"));
        if let Some(t) = found {
            break t;
        }
        assert!(Instant::now() < deadline, "no temporary file appeared");
        std::thread::sleep(Duration::from_millis(10));
    };
    kill(&child, "-TERM");
    let run = wait_at_most(child, Duration::from_secs(20), "mesh after SIGTERM");
    refused(&run, "interrupted by SIGTERM", "SIGTERM during mesh");
    assert!(!dir.path().join(&temp).exists(), "{temp} was removed");
    assert_eq!(names(dir.path()), ["gyroid_sphere.rhai"]);
}

#[test]
fn a_terminated_fake_printer_writes_its_log() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("executed.tsv");
    let mut child = Command::new(isoforge_bin())
        .args(["fake-printer", "--log", s(&log)])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("fake-printer starts");
    // The first line (the pty path) says it is serving.
    let mut first = [0u8; 5];
    child
        .stdout
        .as_mut()
        .expect("piped")
        .read_exact(&mut first)
        .expect("the pty path");
    assert_eq!(&first, b"/dev/");
    kill(&child, "-TERM");
    let run = wait_at_most(child, Duration::from_secs(10), "fake-printer after SIGTERM");
    assert_eq!(run.status.code(), Some(0));
    assert_eq!(names(dir.path()), ["executed.tsv"], "the log, no temporary");
}
