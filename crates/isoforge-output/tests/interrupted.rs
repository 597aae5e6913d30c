//! What a signal handler does before exiting: `remove_temp_files` removes the temporaries of
//! every output not yet committed, and nothing can be written after it. (Its own test
//! binary, because it closes the process-wide registry for good.)

use std::io::Write;

use isoforge_output::{
    Options, OutputError, OutputFile, OutputFolder, live_temp_files, remove_temp_files,
};

#[test]
fn remove_temp_files_leaves_nothing_and_closes_the_door() {
    let dir = tempfile::tempdir().unwrap();
    let old = dir.path().join("old.stl");
    std::fs::write(&old, b"old").unwrap();
    let mut replacing = OutputFile::prepare(&old, Options::default()).unwrap();
    replacing.write_all(b"half of the new").unwrap();
    let new = OutputFile::prepare(&dir.path().join("new.stl"), Options::default()).unwrap();
    let mut folder = OutputFolder::prepare(&dir.path().join("layers"), Options::default()).unwrap();
    folder.write("00000.png", b"png").unwrap();
    let live = live_temp_files();
    assert_eq!(live.len(), 3, "{live:?}");
    assert!(live.iter().all(|p| p.exists()));

    assert_eq!(remove_temp_files(), 3);
    assert!(live.iter().all(|p| !p.exists()));
    assert!(live_temp_files().is_empty());
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["old.stl"], "only what was there before");
    assert_eq!(std::fs::read(&old).unwrap(), b"old");

    // The outputs in flight fail, and nothing new starts.
    assert!(matches!(
        replacing.commit(),
        Err(OutputError::Interrupted { .. })
    ));
    assert!(matches!(new.commit(), Err(OutputError::Interrupted { .. })));
    assert!(matches!(
        folder.commit(),
        Err(OutputError::Interrupted { .. })
    ));
    assert!(matches!(
        OutputFile::prepare(&dir.path().join("later.stl"), Options::default()),
        Err(OutputError::Interrupted { .. })
    ));
    assert_eq!(std::fs::read(&old).unwrap(), b"old");
}
