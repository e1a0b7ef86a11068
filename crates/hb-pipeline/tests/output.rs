//! Result files written atomically: errors that name what went wrong, and no partial file left.

use hb_pipeline::output::{OutputError, check_output_path, write_atomically};

#[test]
fn errors_name_what_went_wrong_and_leave_no_file() {
    let dir = tempfile::tempdir().unwrap();
    assert!(matches!(
        check_output_path(dir.path()),
        Err(OutputError::IsAFolder(p)) if p == dir.path()
    ));
    let missing = dir.path().join("no/such/file.csv");
    assert!(matches!(
        write_atomically(&missing, |_| Ok(())),
        Err(OutputError::NoSuchFolder(p)) if p == dir.path().join("no/such")
    ));
    let target = dir.path().join("file.csv");
    let failed = write_atomically(&target, |w| {
        w.write_all(b"half")?;
        Err(std::io::Error::other("disk full"))
    });
    match failed {
        Err(OutputError::Write { path, source }) => {
            assert_eq!(path, target);
            assert_eq!(source.to_string(), "disk full");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    write_atomically(&target, |w| w.write_all(b"whole")).unwrap();
    assert_eq!(std::fs::read(&target).unwrap(), b"whole");
}

/// A symbolic link is written through (its file replaced, the link kept), also along a chain of
/// links; a device is written in place, never replaced by a regular file.
#[cfg(unix)]
#[test]
fn links_are_written_through_and_devices_in_place() {
    use hb_pipeline::output::output_target;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("model.json");
    std::fs::write(&file, "old").unwrap();
    let link = dir.path().join("link.json");
    let chain = dir.path().join("chain.json");
    std::os::unix::fs::symlink("model.json", &link).unwrap();
    std::os::unix::fs::symlink(&link, &chain).unwrap();
    assert_eq!(output_target(&chain), (file.clone(), false));
    write_atomically(&chain, |w| w.write_all(b"new")).unwrap();
    assert!(
        std::fs::symlink_metadata(&chain)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "new");
    // A link to a file not there yet makes the file.
    let dangling = dir.path().join("dangling.json");
    std::os::unix::fs::symlink("later.json", &dangling).unwrap();
    write_atomically(&dangling, |w| w.write_all(b"made")).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.path().join("later.json")).unwrap(),
        "made"
    );
    // A device: written in place, still a device afterwards.
    let null = std::path::Path::new("/dev/null");
    assert_eq!(output_target(null), (null.to_owned(), true));
    write_atomically(null, |w| w.write_all(b"gone")).unwrap();
    assert!(!std::fs::metadata(null).unwrap().is_file());
}
