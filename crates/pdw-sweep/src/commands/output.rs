//! The files a command writes, claimed before anything is computed: the library's one claim
//! ([`pdw::output`]), which every subcommand goes through.

pub use pdw::output::*;
