//! Parameter families of models as trait objects. A family `μ ↦ model` is any closure returning
//! `Result<Box<S>, E>` (`S` a section model, `E` a displayable error); every such closure is a
//! [`ModelFamily`], which hands the model over as `dyn Section` and the error as text. The
//! continuation, codimension-two and orbit-diagram algorithms take `&dyn ModelFamily`, so they
//! are compiled once, in this crate, instead of once per model type and closure in every crate
//! that calls them.

use pdw_hybrid::Section;
use std::fmt::Display;

/// A model built by a family, owned, seen as a section model.
pub trait Built: Send + Sync {
    /// The model.
    fn section(&self) -> &dyn Section;
}

impl<S: Section + ?Sized> Built for Box<S> {
    fn section(&self) -> &dyn Section {
        (**self).as_section()
    }
}

/// A one-parameter family of models, `μ ↦ model`, with its errors as text; `'m` bounds the
/// borrows a model may hold. Implemented by every closure `Fn(f64) -> Result<Box<S>, E>`.
pub trait ModelFamily<'m> {
    /// The model at `mu`, or why it cannot be built.
    fn build(&self, mu: f64) -> Result<Box<dyn Built + 'm>, String>;
}

/// A two-parameter family of models, `(p_step, p_free) ↦ model`, with its errors as text.
/// Implemented by every closure `Fn(f64, f64) -> Result<Box<S>, E>`.
pub trait ModelFamily2<'m> {
    /// The model at `(a, b)`, or why it cannot be built.
    fn build(&self, a: f64, b: f64) -> Result<Box<dyn Built + 'm>, String>;
}

impl<'m, S, E, F> ModelFamily<'m> for F
where
    S: Section + ?Sized + 'm,
    E: Display,
    F: Fn(f64) -> Result<Box<S>, E>,
{
    fn build(&self, mu: f64) -> Result<Box<dyn Built + 'm>, String> {
        match self(mu) {
            Ok(m) => Ok(Box::new(m)),
            Err(e) => Err(e.to_string()),
        }
    }
}

impl<'m, S, E, F> ModelFamily2<'m> for F
where
    S: Section + ?Sized + 'm,
    E: Display,
    F: Fn(f64, f64) -> Result<Box<S>, E>,
{
    fn build(&self, a: f64, b: f64) -> Result<Box<dyn Built + 'm>, String> {
        match self(a, b) {
            Ok(m) => Ok(Box::new(m)),
            Err(e) => Err(e.to_string()),
        }
    }
}
