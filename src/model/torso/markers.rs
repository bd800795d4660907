//! Marker outputs of [`Torso`]: the SLP grid on the skin, read lazily once per state, and
//! the whole deformed skin on request.

use super::Torso;
use crate::anatomy::skin::MarkerSet;
use crate::observe::markers::{MAX_MARKERS, MarkerModel, MarkerOutputs, MarkerScene};
use crate::{Error, Result};
use nalgebra::Point3;
use std::sync::Arc;

impl Torso {
    /// The marker grid this instance reads: `scene.grid_rows` x `scene.grid_cols`,
    /// registered to `scene.slp_reference` when set.
    pub fn marker_scene(&self) -> MarkerScene {
        MarkerScene {
            rows: self.config.scene.grid_rows,
            cols: self.config.scene.grid_cols,
            slp_reference: self.config.scene.slp_reference.clone(),
            set: self.marker_set.clone(),
        }
    }

    /// Reads the markers of `set` (bound to the rest skin, model frame) instead of the grid;
    /// `None` returns to the grid. The marker model is built on the next read.
    pub fn set_marker_set(&mut self, set: Option<Arc<MarkerSet>>) {
        self.marker_set = set;
        self.markers = MarkerOutputs::default();
    }

    /// The marker set read instead of the grid, if any.
    pub fn marker_set(&self) -> Option<&Arc<MarkerSet>> {
        self.marker_set.as_ref()
    }

    /// Number of markers read: the grid's (rows x columns) or the set's.
    pub fn marker_count(&self) -> usize {
        match &self.marker_set {
            Some(s) => s.len(),
            None => self.config.scene.grid_rows * self.config.scene.grid_cols,
        }
    }

    /// The marker model (skin, weights, grid, registration), built on first use (a few tenths
    /// of a second) and shared by every instance of the compiled model.
    pub fn marker_model(&mut self) -> Result<Arc<MarkerModel>> {
        let scene = self.marker_scene();
        let compiled = &self.compiled;
        self.markers
            .model(|| {
                compiled
                    .markers
                    .get_or_build(&scene, &compiled.anatomy, &compiled.model)
            })
            .cloned()
    }

    /// Marker positions of the current state [m], row-major from the top row, column 0 on
    /// the subject's right; in the recording's frame when the grid is registered
    /// (`scene.slp_reference`), otherwise in the model frame. Computed once per state: only
    /// the markers' skin points are blended.
    pub fn markers(&mut self) -> Result<&[Point3<f64>]> {
        if self.markers.is_valid() {
            // read again at the same state (the FMU reads one value at a time): no scene
            return Ok(self.markers.cached());
        }
        self.current_positions();
        let scene = self.marker_scene();
        let compiled = &self.compiled;
        self.markers.positions(
            || {
                compiled
                    .markers
                    .get_or_build(&scene, &compiled.anatomy, &compiled.model)
            },
            &self.y,
        )
    }

    /// The whole deformed skin of the current state in the markers' frame (for export and the
    /// C ABI); triangles: `marker_model()?.skin().triangles`.
    pub fn skin_vertices(&mut self, out: &mut Vec<Point3<f64>>) -> Result<()> {
        self.current_positions();
        let scene = self.marker_scene();
        let compiled = &self.compiled;
        self.markers.skin(
            || {
                compiled
                    .markers
                    .get_or_build(&scene, &compiled.anatomy, &compiled.model)
            },
            &self.y,
            out,
        )
    }

    /// Positions of every anatomy anchor at the current state (rib, sternum and abdominal
    /// points; index as in [`crate::anatomy::Anatomy::anchors`]), for exports.
    pub fn anchor_positions(&mut self) -> &[Point3<f64>] {
        self.observation();
        &self.data.pos
    }

    /// Marker `index` (0-based: the grid's `marker[index + 1]`, or the set's `index`-th)
    /// coordinate `axis` (0 x, 1 y, 2 z) [m]. Indices from the marker count up to 255 (the
    /// most markers a grid or an FMU has) read 0.0 without building the skin.
    pub(super) fn read_marker(&mut self, index: u16, axis: u8) -> Result<f64> {
        let (index, axis) = (index as usize, axis as usize);
        if axis > 2 {
            return Err(Error::invalid("marker axis", axis, "0 (x), 1 (y) or 2 (z)"));
        }
        if index >= MAX_MARKERS {
            return Err(Error::invalid(
                "marker index",
                index,
                format!("0..{MAX_MARKERS}"),
            ));
        }
        if index >= self.marker_count() {
            return Ok(0.0);
        }
        Ok(self.markers()?[index][axis])
    }
}
