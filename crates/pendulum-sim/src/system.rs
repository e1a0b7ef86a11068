//! Second-order systems `x'' = F(t, x, x')`: the trait every system implements (the oscillators
//! of this crate, a system in a record's frame, every identified model), and the branches of a
//! system that switches at rest, defined in the vocabulary crate (`circle_signal::system`) so
//! that the models' crate needs no simulator to implement them.

pub use circle_signal::system::{Branch, SecondOrderSystem};
