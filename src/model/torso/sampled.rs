//! Runs read at many output times without stopping the solver at each of them: the states
//! between steps come from the method's continuous extension (dense output, Hairer, Norsett
//! & Wanner, *Solving ODEs I*, Sec. II.6), so a recording's 56 Hz frames do not shorten the
//! steps. Used by fits and synthetic recordings, which read markers at every frame.

use super::{AdvanceStats, Torso};
use crate::model::Quantity;
use crate::{Error, Result};
use nalgebra::Point3;

/// Largest number of interpolated states held at once by [`Torso::advance_sampled`]: the
/// run ends a step exactly on every this-many-th output time, which bounds the memory
/// (64 states of 2,575 values at level of detail 1 are 1.3 MB) at the cost of one shortened
/// step per 64 outputs.
const CHUNK: usize = 64;

/// A state reached by [`Torso::advance_sampled`], as the visitor sees it: its time, its
/// state vector, the quantities and the markers read off it.
pub struct Sample<'a> {
    torso: &'a mut Torso,
}

impl Sample<'_> {
    /// Time of the sample [s].
    pub fn time(&self) -> f64 {
        self.torso.time
    }

    /// The state vector of the sample (layout: [`crate::dynamics::Layout`]).
    pub fn state(&self) -> &[f64] {
        &self.torso.y
    }

    /// A quantity of the sample, as [`Torso::read`].
    pub fn read(&mut self, quantity: Quantity) -> Result<f64> {
        self.torso.read(quantity)
    }

    /// The markers of the sample, as [`Torso::markers`].
    pub fn markers(&mut self) -> Result<&[Point3<f64>]> {
        self.torso.markers()
    }
}

impl Torso {
    /// Advances to `t_end` as [`Torso::advance_to`] does, and calls `visit(k, sample)` with
    /// the state at each `times[k]` in order. `times` must be finite, non-decreasing and
    /// within [current time, `t_end`]. The solver does not stop at the output times (except
    /// at every 64th): their states are interpolated by the method's continuous extension,
    /// whose error is of the order of the local error the tolerances allow. The run ends at
    /// `t_end` with the same state as [`Torso::advance_to`] up to that tolerance.
    ///
    /// On an error (bad arguments, a failed step, an error returned by `visit`) the
    /// instance is left at its last good time: the start for bad arguments, otherwise the
    /// end of the last completed stretch of outputs.
    pub fn advance_sampled(
        &mut self,
        t_end: f64,
        times: &[f64],
        visit: &mut dyn FnMut(usize, &mut Sample<'_>) -> Result<()>,
    ) -> Result<AdvanceStats> {
        if !t_end.is_finite() || t_end < self.time {
            return Err(Error::invalid(
                "time",
                t_end,
                format!("a finite time >= the current time {}", self.time),
            ));
        }
        if let Some(i) = times
            .iter()
            .position(|t| !t.is_finite() || *t < self.time || *t > t_end)
        {
            return Err(Error::invalid(
                format!("output time [{i}]"),
                times[i],
                format!("a finite time in [{}, {t_end}]", self.time),
            ));
        }
        if let Some(i) = times.windows(2).position(|w| w[1] < w[0]) {
            return Err(Error::invalid(
                format!("output time [{}]", i + 1),
                times[i + 1],
                format!("non-decreasing (>= output time [{i}] = {})", times[i]),
            ));
        }
        let before = self.integrator.stats();
        let n = self.y.len();
        let mut k = 0;
        let mut states: Vec<f64> = Vec::with_capacity(CHUNK.min(times.len()) * n);
        let mut end_state = vec![0.0; n];
        loop {
            // outputs at the current time are the current state
            while k < times.len() && times[k] == self.time {
                visit(k, &mut Sample { torso: self })?;
                k += 1;
            }
            if k == times.len() {
                break;
            }
            let end = (k + CHUNK).min(times.len());
            let stretch_end = times[end - 1];
            states.clear();
            self.integrate_dense(stretch_end, &times[k..end], &mut states)?;
            if states.len() != (end - k) * n {
                return Err(Error::State(format!(
                    "the solver interpolated {} of {} output states",
                    states.len() / n,
                    end - k
                )));
            }
            // Visit the interpolated states one by one in the instance itself, then put the
            // stretch's end state back (bit for bit, so the solver's FSAL stage stays valid).
            end_state.copy_from_slice(&self.y);
            let mut outcome = Ok(());
            for (j, y) in states.chunks_exact(n).enumerate() {
                self.y.copy_from_slice(y);
                self.time = times[k + j];
                self.observation = None;
                self.markers.invalidate();
                outcome = visit(k + j, &mut Sample { torso: self });
                if outcome.is_err() {
                    break;
                }
            }
            self.y.copy_from_slice(&end_state);
            self.time = stretch_end;
            self.observation = None;
            self.markers.invalidate();
            outcome?;
            k = end;
        }
        if t_end > self.time {
            self.advance_to(t_end)?;
        }
        let after = self.integrator.stats();
        Ok(AdvanceStats {
            steps: after.steps - before.steps,
            rejected: after.rejected - before.rejected,
            rhs_evaluations: after.rhs_evaluations - before.rhs_evaluations,
        })
    }

    /// Integrates to `t_end`, appending the interpolated state at each of `outputs` (in
    /// (time, t_end]) to `states`.
    fn integrate_dense(
        &mut self,
        t_end: f64,
        outputs: &[f64],
        states: &mut Vec<f64>,
    ) -> Result<()> {
        let (mut system, y, time, integrator) = self.integration_parts();
        let result = integrator.integrate_dense(&mut system, time, y, t_end, outputs, |_, ys| {
            states.extend_from_slice(ys)
        });
        self.observation = None;
        self.markers.invalidate();
        result.map_err(|e| Error::Numerical {
            time: self.time,
            reason: e.to_string(),
        })
    }
}
