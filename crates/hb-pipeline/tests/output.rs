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
