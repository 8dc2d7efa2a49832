//! Pure 2D math for camera alignment on a CNC machine.
//!
//! * [`pixel`]: the pixel chain of SPEC §2, `O = C + K·R·(p − res/2 − PxCenterOffset)`, and its
//!   inverse.
//! * [`fit`]: closed-form least-squares fits from commanded to observed points — rigid,
//!   similarity, rectangle (the true 5-parameter minimum) and affine — and the 2×2 solve
//!   calibration needs.
//! * [`lens`]: lens distortion (Brown–Conrady) about the optical centre, and its inverse.
//! * [`chain`]: the `G51 → G68 → G52` modal chain M282 emits, its exact `apply`, and the fixed
//!   decimals its text is written with (`vision-mcode` writes the text).
//! * [`linuxcnc`]: the same alignment as LinuxCNC executes it (a G5x rotation and a `G52`
//!   shift, no scale).
//! * [`units`]: inch ↔ millimetre.
//!
//! No I/O, no allocation on the fit path, no NaN: every degenerate input is a [`MathError`].
//!
//! ```
//! use vision_math::{fit_rectangle, Point2};
//!
//! // The manual's example 4: marks at the corners of a 6 × 4 in part, found slightly off.
//! let commanded = [Point2::new(0.0, 0.0), Point2::new(6.0, 0.0), Point2::new(6.0, 4.0), Point2::new(0.0, 4.0)];
//! let observed = [Point2::new(0.10, 0.05), Point2::new(6.10, 0.08), Point2::new(6.07, 4.08), Point2::new(0.07, 4.05)];
//! let fit = fit_rectangle(&commanded, &observed)?;
//! let chain = fit.transform.chain().expect("a rectangle fit is expressible as G51/G68/G52");
//! for (n, o) in commanded.iter().zip(&observed) {
//!     assert!((chain.apply(*n) - o).norm() <= fit.max_residual + 1e-12);
//! }
//! chain.check()?;
//! # Ok::<(), vision_math::MathError>(())
//! ```

pub mod bounds;
pub mod centre;
pub mod chain;
mod error;
pub mod fit;
pub mod lens;
pub mod lens_fit;
pub mod linuxcnc;
#[cfg(test)]
mod normal;
pub mod pixel;
pub mod scale;
pub mod show;
pub mod units;

pub use centre::{fit_centre, CentreFit};
pub use chain::AlignmentChain;
pub use error::MathError;
pub use fit::{
    fit_affine, fit_piece, fit_rectangle, fit_rigid, fit_similarity, solve_linear, Fit, LinearFit, Model, PartialFit,
    Piece, Transform,
};
pub use lens::Lens;
pub use lens_fit::{fit_lens, LensFit, LensFitStart, WalkReading};
pub use nalgebra::{Matrix2, Point2, UnitComplex, Vector2};
pub use pixel::{PixelChain, Remap};
pub use scale::{image_turn, ImageTurn, ScaleEstimate, ScaleEvidence};
pub use units::{inch_to_mm, mm_to_inch, LengthUnit, MM_PER_INCH};
