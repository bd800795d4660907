//! Outputs by name: [`Torso::read_output`], the one way the FMU and the C ABI report a
//! quantity (markers beyond the marker count, solver statistics, and an error naming the
//! output when a value cannot be read or is not finite).

use super::{Quantity, Torso};
use crate::{Error, Result};

impl Torso {
    /// Reads the output `name` (as the FMU calls it) of quantity `q`: markers beyond the
    /// marker count (the grid's `rows x cols`, or a marker set's size) read 0, solver
    /// statistics come from the integrator's counters, everything else from [`Torso::read`]
    /// (which computes the observation once per state). What the model cannot provide, and
    /// any non-finite value, is an error naming `name`.
    pub fn read_output(&mut self, name: &str, q: Quantity) -> Result<f64> {
        if let Quantity::Marker { index, .. } = q
            && usize::from(index) >= self.marker_count()
        {
            return Ok(0.0);
        }
        let value = match q {
            Quantity::SolverSteps => self.solver_stats().steps as f64,
            Quantity::SolverRejectedSteps => self.solver_stats().rejected as f64,
            Quantity::SolverRhsEvaluations => self.solver_stats().rhs_evaluations as f64,
            q => self
                .read(q)
                .map_err(|e| Error::State(format!("cannot read `{name}`: {e}")))?,
        };
        if !value.is_finite() {
            return Err(Error::Numerical {
                time: self.time(),
                reason: format!("`{name}` is not finite ({value})"),
            });
        }
        Ok(value)
    }
}
