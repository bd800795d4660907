//! Generic numerical tools that know nothing of torsos, shared by [`crate::fit`] and
//! [`crate::stats`]: derivative-free minimisers over a box and a seeded random number
//! generator. A room of its own so that neither of its users reaches into the other.
//!
//! | file | owns |
//! |---|---|
//! | [`optimize`] | bounded Nelder-Mead (Gao & Han coefficients), multi-start, CMA-ES |
//! | [`rng`] | seeded PCG64 generator and its uniform, normal, gamma and beta variates |

pub mod optimize;
pub mod rng;
