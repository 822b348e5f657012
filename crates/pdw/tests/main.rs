//! The library's tests, one binary: the value syntaxes of the front ends ([`input`]) and the
//! walk's setup ([`simulate`]).

mod design;
mod gsn;
mod input;
mod mfpt;
mod simulate;
