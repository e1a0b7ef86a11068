//! The texts of the errors: locations, missing columns that say what there is, and no option of a
//! command line named.
use hb_record::input::{Column, InputError, Location, Role};

#[test]
fn locations_read_as_before() {
    assert_eq!(Location::Line(12).to_string(), "line 12");
    assert_eq!(Location::Sample(12).to_string(), "sample 12");
}

#[test]
fn missing_columns_say_what_there_is() {
    let missing = |wanted, found: &[&str], width| InputError::MissingColumn {
        role: Role::Time,
        wanted,
        found: found.iter().map(|&c| c.to_owned()).collect(),
        width,
    };
    assert_eq!(
        missing(Column::Name("t".into()), &["time", "theta"], 2).to_string(),
        "no time column 't' in the input (columns: time,theta)"
    );
    assert_eq!(
        missing(Column::Position(3), &[], 2).to_string(),
        "no time column 3 in the input (2 unnamed columns)"
    );
    assert_eq!(
        missing(Column::Name("t".into()), &[], 2).to_string(),
        "no time column 't' in the input (2 unnamed columns: give a position)"
    );
}

#[test]
fn texts_name_no_command_line_options() {
    for e in [
        InputError::NeedStep,
        InputError::TimeTwice,
        InputError::BadStep { dt: 0.0 },
        InputError::BadDrivePeriod { period: -1.0 },
        InputError::MissingColumn {
            role: Role::Angle,
            wanted: Column::Position(2),
            found: Vec::new(),
            width: 1,
        },
    ] {
        assert!(!e.to_string().contains("--"), "{e}");
    }
}
