//! One test (or property) per rule of the crate docs.

use std::fs;
use std::io::{Read, Write};
use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::{Path, PathBuf};

use proptest::prelude::*;

use crate::registry::{Closed, Registry, TempKind};
use crate::{Durability, Options, OutputError, OutputFile, OutputFolder, Streams, write_file};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .expect("readable folder")
        .map(|e| e.expect("entry").file_name().into_string().expect("utf-8"))
        .collect();
    v.sort();
    v
}

fn mode(p: &Path) -> u32 {
    fs::metadata(p).expect("exists").permissions().mode() & 0o7777
}

fn opts<'a>(inputs: &'a [&'a Path]) -> Options<'a> {
    Options::with_inputs(inputs)
}

#[test]
fn a_new_file_appears_only_on_commit_with_the_usual_mode() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("a.stl");
    let mut file = OutputFile::prepare(&out, Options::default()).unwrap();
    file.write_all(b"half").unwrap();
    assert!(!out.exists(), "nothing at the path before commit");
    let temp = file.temp_path().unwrap().to_path_buf();
    assert!(temp.exists() && temp.parent() == Some(dir.path()));
    file.write_all(b" and whole").unwrap();
    file.commit().unwrap();
    assert_eq!(fs::read(&out).unwrap(), b"half and whole");
    assert_eq!(names(dir.path()), ["a.stl"]);
    // The mode a plain create gives (0666 less the umask), not mkstemp's 0600.
    let plain = dir.path().join("plain");
    fs::write(&plain, b"").unwrap();
    assert_eq!(mode(&out), mode(&plain));
}

#[test]
fn dropped_uncommitted_leaves_the_old_file_and_no_temp() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("keep.txt");
    fs::write(&out, b"old").unwrap();
    {
        let mut file = OutputFile::prepare(&out, Options::default()).unwrap();
        file.write_all(b"new but unfinished").unwrap();
    }
    assert_eq!(fs::read(&out).unwrap(), b"old");
    assert_eq!(names(dir.path()), ["keep.txt"]);
}

#[test]
fn write_with_passes_the_work_error_through_and_writes_nothing() {
    #[derive(Debug)]
    enum Work {
        Failed,
        Output,
    }
    impl From<OutputError> for Work {
        fn from(_: OutputError) -> Work {
            Work::Output
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.bin");
    let file = OutputFile::prepare(&out, Options::default()).unwrap();
    let r = file.write_with(|w| {
        w.write_all(b"partial").map_err(|_| Work::Output)?;
        Err(Work::Failed)
    });
    assert!(matches!(r, Err(Work::Failed)));
    assert!(names(dir.path()).is_empty());
    let file = OutputFile::prepare(&out, Options::default()).unwrap();
    file.write_with(|w| w.write_all(b"ok").map_err(|_| Work::Output))
        .unwrap();
    assert_eq!(fs::read(&out).unwrap(), b"ok");
}

#[test]
fn an_input_is_refused_whatever_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("heart.rhai");
    fs::write(&input, b"Sphere(1)").unwrap();
    let hard = dir.path().join("hard.rhai");
    fs::hard_link(&input, &hard).unwrap();
    let soft = dir.path().join("soft.rhai");
    std::os::unix::fs::symlink("heart.rhai", &soft).unwrap();
    let spelled = dir
        .path()
        .join(".")
        .join("sub")
        .join("..")
        .join("heart.rhai");
    fs::create_dir(dir.path().join("sub")).unwrap();
    for out in [&input, &hard, &soft, &spelled] {
        let err = OutputFile::prepare(out, opts(&[&input])).unwrap_err();
        assert!(
            matches!(&err, OutputError::IsInput { input: i, .. } if i == &input),
            "{}: {err}",
            out.display()
        );
        assert!(err.to_string().contains("input"), "{err}");
        let err = write_file(out, b"x", opts(&[&input])).unwrap_err();
        assert!(matches!(err, OutputError::IsInput { .. }));
    }
    assert_eq!(fs::read(&input).unwrap(), b"Sphere(1)");
    assert_eq!(
        names(dir.path()),
        ["hard.rhai", "heart.rhai", "soft.rhai", "sub"]
    );
}

#[test]
fn a_symlink_stays_a_link_and_its_target_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let real_dir = dir.path().join("real");
    fs::create_dir(&real_dir).unwrap();
    let target = real_dir.join("mesh.stl");
    fs::write(&target, b"old").unwrap();
    fs::set_permissions(&target, fs::Permissions::from_mode(0o640)).unwrap();
    // A relative link, through a second (absolute) link.
    let link1 = dir.path().join("link1.stl");
    std::os::unix::fs::symlink("real/mesh.stl", &link1).unwrap();
    let link2 = dir.path().join("link2.stl");
    std::os::unix::fs::symlink(&link1, &link2).unwrap();
    write_file(&link2, b"new", Options::default()).unwrap();
    assert!(
        fs::symlink_metadata(&link2)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(
        fs::symlink_metadata(&link1)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(fs::read(&target).unwrap(), b"new");
    assert_eq!(mode(&target), 0o640);
    // The temporary went beside the target, and is gone.
    assert_eq!(names(&real_dir), ["mesh.stl"]);
    // A dangling link: its target is created.
    let dangling = dir.path().join("dangling.stl");
    std::os::unix::fs::symlink("real/new.stl", &dangling).unwrap();
    write_file(&dangling, b"fresh", Options::default()).unwrap();
    assert!(
        fs::symlink_metadata(&dangling)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(fs::read(real_dir.join("new.stl")).unwrap(), b"fresh");
}

#[test]
fn a_symlink_loop_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    std::os::unix::fs::symlink(&b, &a).unwrap();
    std::os::unix::fs::symlink(&a, &b).unwrap();
    let err = OutputFile::prepare(&a, Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::SymlinkLoop { .. }), "{err}");
}

#[test]
fn a_read_only_file_is_refused_and_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ro.gcode");
    fs::write(&out, b"keep me").unwrap();
    fs::set_permissions(&out, fs::Permissions::from_mode(0o444)).unwrap();
    let err = write_file(&out, b"x", Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::ReadOnly { .. }), "{err}");
    assert!(err.to_string().contains("read-only"));
    assert_eq!(fs::read(&out).unwrap(), b"keep me");
    assert_eq!(names(dir.path()), ["ro.gcode"]);
}

#[test]
fn a_missing_folder_or_a_folder_at_the_path_is_refused_at_prepare() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("no").join("such").join("x.stl");
    let err = OutputFile::prepare(&out, Options::default()).unwrap_err();
    assert!(
        matches!(&err, OutputError::NoFolder { folder, .. } if folder.ends_with("no/such")),
        "{err}"
    );
    let err = OutputFile::prepare(dir.path(), Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::IsFolder { .. }), "{err}");
    let file = dir.path().join("f");
    fs::write(&file, b"").unwrap();
    let err = OutputFile::prepare(&file.join("x.stl"), Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::NotAFolder { .. }), "{err}");
    let err = OutputFile::prepare(Path::new(""), Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::EmptyPath));
}

#[test]
fn devices_are_written_through_or_refused() {
    // /dev/null takes anything and stays a device.
    write_file(Path::new("/dev/null"), b"discarded", Options::default()).unwrap();
    assert!(
        fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device()
    );
    // /dev/full fails the write, and says so.
    let err = write_file(Path::new("/dev/full"), b"x", Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::Write { .. }), "{err}");
    let refuse = Options {
        streams: Streams::Refuse,
        ..Options::default()
    };
    let err = write_file(Path::new("/dev/null"), b"x", refuse).unwrap_err();
    assert!(
        matches!(
            err,
            OutputError::Unsupported {
                kind: "character device",
                ..
            }
        ),
        "{err}"
    );
}

#[test]
fn a_fifo_is_written_into_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut s = String::new();
            fs::File::open(&fifo)
                .unwrap()
                .read_to_string(&mut s)
                .unwrap();
            s
        })
    };
    write_file(&fifo, b"through the pipe", Options::default()).unwrap();
    assert_eq!(reader.join().unwrap(), "through the pipe");
    assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(names(dir.path()), ["pipe"]);
    let refuse = Options {
        streams: Streams::Refuse,
        ..Options::default()
    };
    let err = OutputFile::prepare(&fifo, refuse).unwrap_err();
    assert!(
        matches!(err, OutputError::Unsupported { kind: "FIFO", .. }),
        "{err}"
    );
}

#[test]
fn a_pipe_behind_a_magic_link_is_written_into() {
    // /proc/PID/fd/0 of a `cat` reading a pipe links to "pipe:[N]", which is no path: the
    // output must open the link itself, as it would /dev/stdout.
    let mut cat = std::process::Command::new("cat")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let link = PathBuf::from(format!("/proc/{}/fd/0", cat.id()));
    write_file(&link, b"into the pipe", Options::default()).unwrap();
    drop(cat.stdin.take());
    let mut got = String::new();
    cat.stdout.take().unwrap().read_to_string(&mut got).unwrap();
    cat.wait().unwrap();
    assert_eq!(got, "into the pipe");
}

#[test]
fn durable_writes_replace_like_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("job.journal");
    let sync = Options {
        durability: Durability::Sync,
        streams: Streams::Refuse,
        ..Options::default()
    };
    for k in 0..3 {
        write_file(&out, format!("executed={k}\n").as_bytes(), sync).unwrap();
        assert_eq!(fs::read_to_string(&out).unwrap(), format!("executed={k}\n"));
    }
    assert_eq!(names(dir.path()), ["job.journal"]);
}

#[test]
fn a_folder_output_appears_whole_or_not_at_all() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("layers");
    let mut folder = OutputFolder::prepare(&out, Options::default()).unwrap();
    folder.write("00000.png", b"a").unwrap();
    folder.write("00001.png", b"b").unwrap();
    assert!(!out.exists());
    assert!(folder.write("../escape.png", b"x").is_err());
    folder.commit().unwrap();
    assert_eq!(names(&out), ["00000.png", "00001.png"]);
    assert_eq!(names(dir.path()), ["layers"]);
    // Not empty now: refused.
    let err = OutputFolder::prepare(&out, Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::FolderNotEmpty { .. }), "{err}");
    // An empty folder is replaced and keeps its mode; a dropped one leaves nothing.
    let empty = dir.path().join("empty");
    fs::create_dir(&empty).unwrap();
    fs::set_permissions(&empty, fs::Permissions::from_mode(0o750)).unwrap();
    {
        let mut folder = OutputFolder::prepare(&empty, Options::default()).unwrap();
        folder.write("00000.png", b"a").unwrap();
    }
    assert!(names(&empty).is_empty());
    let mut folder = OutputFolder::prepare(&empty, Options::default()).unwrap();
    folder.write("00000.png", b"a").unwrap();
    folder.commit().unwrap();
    assert_eq!(names(&empty), ["00000.png"]);
    assert_eq!(mode(&empty), 0o750);
    assert_eq!(names(dir.path()), ["empty", "layers"]);
    // A file at the path is not a folder.
    let err = OutputFolder::prepare(&out.join("00000.png"), Options::default()).unwrap_err();
    assert!(matches!(err, OutputError::NotAFolder { .. }), "{err}");
}

#[test]
fn a_closed_registry_creates_and_commits_nothing() {
    let registry = Registry::new();
    let dir = tempfile::tempdir().unwrap();
    let make = |p: &Path| fs::write(p, b"temp");
    let (id1, p1, ()) = registry
        .create(dir.path(), TempKind::File, make)
        .unwrap()
        .unwrap();
    let (_, p2, ()) = registry
        .create(dir.path(), TempKind::Folder, |p| fs::create_dir(p))
        .unwrap()
        .unwrap();
    fs::write(p2.join("inside"), b"").unwrap();
    assert_ne!(p1, p2);
    assert_eq!(registry.live(), vec![p1.clone(), p2.clone()]);
    assert_eq!(registry.remove_all(), 2);
    assert!(!p1.exists() && !p2.exists());
    assert!(names(dir.path()).is_empty());
    assert_eq!(
        registry.create(dir.path(), TempKind::File, make).err(),
        Some(Closed)
    );
    let dest = dir.path().join("dest");
    assert_eq!(
        registry.commit(id1, || fs::write(&dest, b"")).err(),
        Some(Closed)
    );
    assert!(!dest.exists(), "a closed registry runs no rename");
}

#[test]
fn a_taken_temp_name_is_skipped() {
    let registry = Registry::new();
    let dir = tempfile::tempdir().unwrap();
    let first: PathBuf = dir
        .path()
        .join(format!(".isoforge-{}-1.tmp", std::process::id()));
    fs::write(&first, b"someone else's").unwrap();
    let (_, p, ()) = registry
        .create(dir.path(), TempKind::File, |p| {
            fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(p)
                .map(|_| ())
        })
        .unwrap()
        .unwrap();
    assert_ne!(p, first);
    assert_eq!(fs::read(&first).unwrap(), b"someone else's");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Whatever is written and wherever the writer stops, the path holds the old content or
    /// the new content, whole, and no temporary is left.
    #[test]
    fn whole_or_not_at_all(
        old in proptest::option::of(proptest::collection::vec(any::<u8>(), 0..2000)),
        new in proptest::collection::vec(any::<u8>(), 0..5000),
        stop_at in any::<proptest::sample::Index>(),
        commit in any::<bool>(),
    ) {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.bin");
        if let Some(old) = &old {
            fs::write(&out, old).unwrap();
        }
        let mut file = OutputFile::prepare(&out, Options::default()).unwrap();
        let written = if commit { new.len() } else { stop_at.index(new.len() + 1) };
        file.write_all(&new[..written]).unwrap();
        if commit {
            file.commit().unwrap();
            prop_assert_eq!(fs::read(&out).unwrap(), new);
        } else {
            drop(file);
            match &old {
                Some(old) => prop_assert_eq!(&fs::read(&out).unwrap(), old),
                None => prop_assert!(!out.exists()),
            }
        }
        let left = names(dir.path());
        prop_assert!(left.iter().all(|n| n == "out.bin"), "{:?}", left);
    }

    /// A replaced file keeps its permission bits, whatever they were (as long as it is
    /// writable at all).
    #[test]
    fn the_mode_of_a_replaced_file_is_kept(bits in 0u32..0o1000) {
        let mode_before = bits | 0o200;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("kept");
        fs::write(&out, b"old").unwrap();
        fs::set_permissions(&out, fs::Permissions::from_mode(mode_before)).unwrap();
        write_file(&out, b"new", Options::default()).unwrap();
        prop_assert_eq!(mode(&out), mode_before);
        prop_assert_eq!(fs::read(&out).unwrap(), b"new");
    }
}
