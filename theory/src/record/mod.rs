//! The records of the theorem table: rows ([`check`]), the constants they use ([`constant`]) and
//! the certificates behind the rigorous constants ([`certificate`]). Plain data (serialisable),
//! independent of the code that computes them.

pub mod certificate;
pub mod check;
pub mod constant;
