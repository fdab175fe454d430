//! Quantization: world coordinates (`f32`/`f64`) to the integer grid and
//! back — the one place where input is rounded.
//!
//! Notation: `u` — the unit, world length of one grid step; `o` — the world
//! position of grid point 0. A world point `p` maps to `round((p − o) / u)`.

use std::collections::BTreeMap;

use crate::Error;
use crate::exact::IntPoint;

/// A grid in world space: step length and origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quantization {
    unit: f64,
    origin: [f64; 3],
}

impl Quantization {
    /// A grid with step `unit` (world units, e.g. `0.001` for millimetres
    /// in a metre world) and grid point 0 at `origin`.
    ///
    /// # Errors
    /// [`Error::InvalidUnit`] unless `unit` is finite and positive;
    /// [`Error::NonFinite`] for a non-finite origin.
    pub fn new(unit: f64, origin: [f64; 3]) -> Result<Self, Error> {
        if !(unit.is_finite() && unit > 0.0) {
            return Err(Error::InvalidUnit { unit });
        }
        if origin.iter().any(|o| !o.is_finite()) {
            return Err(Error::NonFinite {
                what: "quantization origin",
            });
        }
        Ok(Self { unit, origin })
    }

    /// World length of one grid step.
    #[must_use]
    pub fn unit(&self) -> f64 {
        self.unit
    }

    /// World position of grid point 0.
    #[must_use]
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// The grid point nearest to a world point.
    ///
    /// # Errors
    /// [`Error::NonFinite`] or [`Error::CoordinateOutOfRange`].
    pub fn to_grid(&self, p: [f64; 3]) -> Result<IntPoint, Error> {
        let mut out = [0i64; 3];
        for (axis, o) in out.iter_mut().enumerate() {
            let v = ((p[axis] - self.origin[axis]) / self.unit).round();
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    what: "world coordinate",
                });
            }
            // Saturating: anything beyond i64 fails the range check.
            *o = v as i64;
        }
        IntPoint::from_array(out)
    }

    /// As [`Quantization::to_grid`] for `f32` input.
    ///
    /// # Errors
    /// As [`Quantization::to_grid`].
    pub fn to_grid_f32(&self, p: [f32; 3]) -> Result<IntPoint, Error> {
        self.to_grid(p.map(f64::from))
    }

    /// The world position of a (possibly fractional) grid position.
    #[must_use]
    pub fn to_world(&self, g: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|a| self.origin[a] + g[a] * self.unit)
    }

    /// Volumes per material in cubic grid units, in cubic world units.
    #[must_use]
    pub fn to_world_volumes<K: Ord>(&self, grid: BTreeMap<K, f64>) -> BTreeMap<K, f64> {
        let cube = self.unit * self.unit * self.unit;
        grid.into_iter().map(|(k, v)| (k, v * cube)).collect()
    }
}
