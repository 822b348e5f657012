//! The CLI's value syntaxes ([docs/cli.md](../../../docs/cli.md)): the library's parsers and
//! input error ([`pdw::input`]).

pub use pdw::input::*;
