//! radray: a two-pass renderer. Pass one solves view-independent diffuse radiosity with hemicube form
//! factors; pass two is a Whitted ray tracer whose diffuse term is the radiosity solution.

// `!(x > 0.0)` is how this crate rejects NaN together with out-of-range values; keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod batch;
pub mod burial;
pub mod cache;
pub mod cli;
pub mod compare;
pub mod film;
pub mod info;
pub mod interrupt;
pub mod material;
pub mod mesh;
pub mod output;
pub mod progress;
pub mod radiosity;
pub mod rng;
pub mod run;
pub mod scene;
pub mod sobol;
pub mod trace;
pub mod transport;
