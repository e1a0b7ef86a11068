//! Empty: it lets `xtask` declare the build dependency of `Cargo.toml` that unifies features.

fn main() {}
