//! The operator panel: a local web page that shows what the camera sees — the frame, the mark
//! the finder located on it (circle, centre, diameter, score), the search radius, the mark's
//! offset from the image centre in pixels and machine units, and why no mark was found — with
//! the calibration and telemetry beside it, read-only.
//!
//! A crate of its own, not a module of the CLI: `mach-vision panel` serves a camera's live
//! view with it, and a run (or any host) can serve its own views by publishing them to a
//! [`PanelHandle`] from its own thread, without the CLI. It depends on the camera driver only
//! (frames, their search, and the request reader and PNG encoder its snapshot server uses).
//!
//! * [`Panel`]: the HTTP/1.1 server on `std::net` (routes in `routes`); [`Limits`] bounds it.
//! * [`PanelHandle::publish`]: hands a [`View`] to every page; never waits on a browser.
//! * [`observe`]: one trigger of a [`vision_driver_camera::FrameDriver`] as a [`View`].
//! * [`Fit`]: a run's last fit or calibration beside the frame (`/fit.svg` its picture).
//!
//! Safe by default: loopback only unless a token is given ([`PanelError::TokenRequired`]), and
//! then only for a request naming a loopback host (no DNS rebinding); the
//! token compared in constant time, built-in assets only, bounded requests, clients and event
//! streams, and no route that writes anything or moves the machine.
//!
//! The page's test contract: an element `id="mark"` whose `data-found`, `data-x`, `data-y` and
//! `data-diameter` (pixels, as `mach-vision locate` prints them) and `data-seq` describe the
//! mark on the frame the page shows, `GET /frame.png?seq=N`.
//!
//! ```
//! use vision_panel::{Panel, View};
//!
//! let panel = Panel::bind("127.0.0.1:0".parse()?, None)?;
//! let handle = panel.handle();
//! assert_eq!(handle.publish(View { source: "a test".into(), ..View::default() }), 1);
//! assert!(panel.url().starts_with("http://127.0.0.1:"));
//! // Off loopback, a token is required.
//! assert!(Panel::bind("0.0.0.0:0".parse()?, None).is_err());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod access;
mod error;
mod hub;
mod live;
mod routes;
mod server;
mod view;

pub use error::PanelError;
pub use hub::PanelHandle;
pub use live::{calibration, calibration_line, observe};
pub use server::{Limits, Panel};
pub use view::{Call, Fit, MachineOffset, Mark, Spec, View};

#[cfg(test)]
mod tests;
