//! Validation of a simulated lung volume against spirometry (thesis chapter 4): data
//! preparation (polyphase resampling, lung ratio, offset, alignment by cross-correlation),
//! breathing-frequency estimation, Pearson correlation, Bland-Altman on samples and on
//! breaths, the cosinor model and its equality tests, BARS (Bayesian adaptive regression
//! splines) and its equality test, plots and reports, and a synthetic spirometry generator.
//!
//! Formulas follow the project's statistics reference (methods of Nelson et al. 1979,
//! Bland & Altman 1986, DiMatteo, Genovese & Kass 2001, Behseta & Kass 2005); each file
//! states its equations and sources. The entry point is [`validation::validate`], used by
//! `torso validate`.
//!
//! | file | owns |
//! |---|---|
//! | [`io`] | CSV series with line/column errors |
//! | [`resample`] | polyphase FIR resampling (SciPy `resample_poly` defaults) |
//! | [`prepare`] | flow integration, drift, lung ratio, alignment, offset |
//! | [`frequency`] | breathing frequency: Hann-interpolated DFT, autocorrelation check |
//! | [`agreement`] | Pearson correlation, Bland-Altman |
//! | [`breaths`] | breath segmentation and pairing |
//! | [`ols`] | least squares, F and Wald tests |
//! | [`autoreg`] | regression with AR errors: REML, GLS F test, sieve bootstrap |
//! | [`cosinor`] | cosinor fits and equality tests |
//! | [`bars`] | BARS fits and equality test |
//! | [`special`] | gamma, incomplete beta, t, F, normal distributions |
//! | [`synth`] | synthetic spirometry |
//! | [`thoracoabdominal`] | rib-cage / abdomen phase angle (Lissajous) and rib-cage share |
//! | [`montecarlo`] | size and power of the equality tests by simulation |
//! | [`plot`] | PNG/SVG figures |
//! | [`validation`] | the whole pipeline and its outputs |

pub mod agreement;
pub mod autoreg;
pub mod bars;
pub mod breaths;
pub mod cosinor;
pub mod frequency;
pub mod io;
pub mod montecarlo;
pub mod ols;
pub mod plot;
pub mod prepare;
pub mod resample;
pub mod special;
pub mod synth;
pub mod thoracoabdominal;
pub mod validation;

pub use frequency::{FrequencyEstimate, estimate_frequency};
pub use validation::{Validation, ValidationOptions, validate, write_outputs};
