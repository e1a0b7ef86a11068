//! The command line's options, written where the Python package's tests read them
//! (`python/tests/cli_options.json`), so that a test there holds every Python function's keywords
//! and defaults against the subcommand of the same name. This test fails when the file is not the
//! command line's; `UPDATE_CLI_OPTIONS=1 cargo test -p hbid parity` writes it anew.

use clap::CommandFactory;
use serde_json::{Map, Value, json};

use super::Cli;

/// The subcommands that Python has as functions of the same name.
const COMMANDS: [&str; 5] = ["identify", "simulate", "embed", "upos", "compare"];

/// Every option of `command`: its name with `_` for `-`, its default as the help prints it (null
/// for none), whether it is a flag, and its aliases.
fn options(command: &clap::Command) -> Value {
    let mut out = Map::new();
    for arg in command.get_arguments() {
        let Some(long) = arg.get_long() else {
            // The positional record: Python's first argument.
            continue;
        };
        if long == "help" || long == "version" {
            continue;
        }
        let defaults: Vec<String> = arg
            .get_default_values()
            .iter()
            .map(|v| v.to_string_lossy().into_owned())
            .collect();
        let flag = matches!(arg.get_action(), clap::ArgAction::SetTrue);
        let aliases: Vec<String> = arg
            .get_visible_aliases()
            .unwrap_or_default()
            .into_iter()
            .map(|a| a.replace('-', "_"))
            .collect();
        out.insert(
            long.replace('-', "_"),
            json!({
                "default": defaults.first(),
                "flag": flag,
                "aliases": aliases,
            }),
        );
    }
    Value::Object(out)
}

/// The options of every subcommand Python mirrors.
fn all_options() -> Value {
    let cli = Cli::command();
    let mut out = Map::new();
    for name in COMMANDS {
        let command = cli
            .find_subcommand(name)
            .unwrap_or_else(|| panic!("no subcommand {name}"));
        out.insert(name.to_owned(), options(command));
    }
    Value::Object(out)
}

#[test]
fn the_python_tests_read_the_command_lines_options() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../python/tests/cli_options.json");
    let now = serde_json::to_string_pretty(&all_options()).expect("JSON") + "\n";
    if std::env::var_os("UPDATE_CLI_OPTIONS").is_some() {
        std::fs::write(&path, &now).expect("write cli_options.json");
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == now,
        "{} is not the command line's options: run UPDATE_CLI_OPTIONS=1 cargo test -p hbid parity, then make \
         the Python functions agree (python/tests/test_parity.py)",
        path.display()
    );
}

#[test]
fn every_option_has_a_default_or_none_and_help() {
    let cli = Cli::command();
    for name in COMMANDS {
        let command = cli.find_subcommand(name).expect("subcommand");
        for arg in command.get_arguments() {
            assert!(
                arg.get_help().is_some() || arg.get_long_help().is_some(),
                "{name} --{:?} has no help",
                arg.get_long()
            );
        }
    }
}
