//! How far the output may be from the true surface, in the units the caller thinks in.

use serde::Serialize;

use crate::error::{Error, Result};

/// The largest distance allowed between the output mesh and the surface.
///
/// A relative tolerance is resolved against the diagonal of the bounding box of the
/// input's control points, as loaded: a box known before anything is tessellated, the
/// same on every backend, and kept by a stage for its lifetime, so that ε does not move
/// while the control points are animated.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum Tolerance {
    /// In model units.
    Absolute(f64),
    /// A fraction of the control points' bounding-box diagonal.
    Relative(f64),
}

impl Tolerance {
    /// ε in model units, for a model whose control points' box has diagonal `diag`.
    pub fn resolve(self, diag: f64) -> f64 {
        match self {
            Tolerance::Absolute(eps) => eps,
            Tolerance::Relative(r) => r * diag,
        }
    }

    /// Fails unless the tolerance is a positive, finite number.
    pub fn validate(self) -> Result<()> {
        let value = match self {
            Tolerance::Absolute(v) | Tolerance::Relative(v) => v,
        };
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(Error::Param(format!(
                "tolerance must be a positive number, got {value}"
            )))
        }
    }
}
