//! No code. See Cargo.toml: this crate exists for the dependency features it names.
