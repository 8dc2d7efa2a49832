//! Sub-pixel refinement: a least-squares fit of a blurred-shape model to the pixels near the
//! mark's edges, by damped Gauss–Newton.
//!
//! Model of a pixel at (x, y): `I = P(x, y) + Q(x, y) · M(x, y; g)` where P (background) and Q
//! (contrast) are planes — uneven light, whether it adds or multiplies — and M ∈ [0, 1] is the
//! fraction of the pixel's square covered by the shape blurred by a Gaussian of σ = `s` px
//! (defocus). Each edge is taken as locally straight: M is the [`edge`] profile of the pixel at
//! its depth inside the edge (the Gaussian and the pixel's square, exactly). For a disc,
//! M = edge(R − ρ); for a ring the difference of two such; for a cross the sum of two blurred
//! bars less their overlap, each bar a product of two edge-pair profiles along its axes (exact
//! but at the corners). Least squares on this model is the maximum-likelihood estimate under
//! Gaussian noise, so the centre's spread sits near the Cramér–Rao bound.
//!
//! The blur enters the normal equations as the edge width √(s² + 1/12) (see `edge_width`), s
//! kept at least [`S_MIN`].
//!
//! `model.rs` holds the shapes, `solve.rs` the damped Gauss–Newton fit, `bound.rs` the
//! Cramér–Rao bound of the centre.

mod bound;
mod model;
mod solve;

pub(crate) use bound::crb;
pub(crate) use model::{Annulus, Cross, Disc};
pub(crate) use solve::{fit, FitFailure, FitResult};
#[cfg(test)]
pub(crate) use {model::band, solve::solve};

/// Most parameters: 6 geometric + 6 linear.
pub(crate) const MAXP: usize = 12;

/// Pixel access, generic over the sample type so the inner loops have no branch on depth.
pub(crate) struct Img<'a, T> {
    pub(crate) w: usize,
    pub(crate) h: usize,
    pub(crate) data: &'a [T],
}

impl<T: Copy + Into<f64>> Img<'_, T> {
    #[inline]
    fn at(&self, x: usize, y: usize) -> f64 {
        self.data[y * self.w + x].into()
    }
}
