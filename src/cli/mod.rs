//! What the `cloth3d` command needs beyond the library (feature `cli`): the
//! bench against rapier's cloth, the side-by-side comparison of integrators,
//! PNG plots, and the scene flags shared by the command and the showcase.

pub mod args;
pub mod bench;
pub mod compare;
pub mod plot;
