//! A G-code interpreter for the seed-002 dialect and the Mach alignment modals (work in
//! progress: this step is the parser).
//!
//! ```
//! use vision_gcode::parse::Parser;
//!
//! let mut parser = Parser::new();
//! let block = parser.parse_line("N10 G1 X[1 + 2] Y-#5 (to the corner)", 1)?;
//! assert_eq!(block.line_number(), Some(10));
//! assert_eq!(block.words().len(), 3);
//! assert_eq!(block.comments().next(), Some("to the corner"));
//! # Ok::<(), vision_gcode::GcodeError>(())
//! ```

// The interpreter (next step) uses the crate-internal helpers.
#![allow(dead_code)]

pub mod error;
pub mod expr;
pub mod params;
pub mod parse;

pub use error::{GCode, GcodeError, RunProblem, SyntaxProblem};
