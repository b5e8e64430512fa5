//! radray: a two-pass renderer. Pass one solves view-independent diffuse radiosity with hemicube form
//! factors; pass two is a Whitted ray tracer whose diffuse term is the radiosity solution.

pub mod accel;
pub mod compare;
pub mod film;
pub mod mesh;
pub mod output;
pub mod radiosity;
pub mod rng;
pub mod scene;
pub mod trace;
