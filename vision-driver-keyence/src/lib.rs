//! The Keyence VS-series smart camera, driven over its Non-Procedural command port (TCP 8500),
//! and an emulator that behaves like one (SPEC §7).
//!
//! * [`KeyenceDriver`]: the [`vision_core::CameraDriver`] (`TRG`, `FVR`, `PR`, job switch with
//!   `PL`, falling back to `PW`), one persistent connection, typed errors; [`register`] adds
//!   it to a [`vision_core::DriverRegistry`] as `Keyence`.
//! * [`settings`]: the driver's own settings, `[keyence]` in the profile under the manual's
//!   names (`VisionIP`, `VisionPort`, `VisionTimeout`, `VisionImageWatchDir`,
//!   `VisionImageGrabTimeout`); [`register`] hands them to the registry.
//! * [`KeyenceConfig`]: address, timeout, bounds and the image folder, from those settings.
//! * `images`: M281 D1, the image the camera FTP-pushed for a trigger
//!   ([`vision_core::CameraDriver::grab_image`]).
//! * [`Exchange`]: the pure part — framing, reply parsing and the command/reply state machine
//!   over any `Read + Write` (a transport of your own, e.g. a serial link); the socket is a thin
//!   edge around it. [`parse_data_line`] reads one Data Output line.
//! * `emulator` (cargo feature `emulator`): a TCP server that answers like a VS camera, with
//!   pluggable results and fault injection.
//!
//! ```
//! use vision_core::DriverRegistry;
//! use vision_driver_keyence::emulator::Emulator;
//!
//! let camera = Emulator::builder().bind("127.0.0.1:0")?; // a mark at the image centre
//! let mut registry = DriverRegistry::new();
//! vision_driver_keyence::register(&mut registry);
//! let mut params = registry.params(); // knows the driver's settings by name
//! params.set("VisionIP", "127.0.0.1")?;
//! params.set("VisionPort", i64::from(camera.addr().port()))?;
//! let mut driver = registry.create("Keyence", &params)?;
//! let reading = driver.trigger()?;
//! assert_eq!((reading.x_px, reading.y_px), (888.0, 888.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # What the camera may answer
//!
//! Lines end in CR, CRLF or LF (each one line end; a CRLF split across reads is still one, so a
//! stray LF never shifts replies). To `TRG` the camera echoes `TRG`, then sends one Data Output
//! line, in the same TCP segment or byte by byte. Accepted data lines:
//!
//! | format | example |
//! | --- | --- |
//! | `x,y` (judgment unknown) | `812.125,903.5` |
//! | `judgment,x,y` | `OK,812.125,903.5` or `1,812.125,903.5` |
//! | `judgment,count,x,y,width,height,angle,score` (recommended; count 0 = no mark) | `1,1,812.125,903.5,40.25,39.75,-12.5,97.25` |
//!
//! Numbers plain (`150.0`) or Keyence fixed width (`+0000000888.123000`); judgment `1`/`OK` or
//! `0`/`NG`. NG (a bare `0`/`NG` too) and count 0 are readings (the core turns them into
//! "NG / no mark").
//!
//! # Timeouts
//!
//! [`KeyenceConfig::timeout`] (`VisionTimeout`, 3 s) bounds a whole driver call: connecting when
//! needed, sending, and receiving the complete reply — not each byte, so a peer that dribbles a
//! byte every second cannot hold the driver. After a timeout the connection is dropped: a late
//! reply lands in a dead socket and can never answer the next command.
//!
//! # Errors ([`KeyenceError`] → [`vision_core::DriverErrorKind`])
//!
//! | error | kind | means |
//! | --- | --- | --- |
//! | `ConnectTimeout`, `Unreachable` | Timeout | nothing answered at `VisionIP:VisionPort` |
//! | `Timeout` | Timeout | connected, but the reply did not complete; says whether the echo came (no echo: camera not answering; echo but no data: no Data Output tool) |
//! | `Refused` | Refused | nothing listens on the port |
//! | `Closed` | Refused | the camera closed or reset the connection as it was made or mid-command (another client holds the camera, or it left Run mode) |
//! | `Rejected` | Rejected | `ER,<cmd>,<nn>`, with the code's meaning and the fix for that command; the raw reply is kept in the message |
//! | `Malformed`, `LineTooLong`, `TooManyLines` | Malformed | the reply is not one of the formats, or breaks the bounds (512 bytes a line, 8 lines a reply); the advice follows the command (`TRG`: the Data Output; `PR`/`PL`/`PW`: job switching) |
//! | `Config`, `InvalidJob` | InvalidArgument | refused before anything was sent |
//! | `Resolve`, `Io` | Other | host name does not resolve; another socket error |
//!
//! Every error reads "what happened — what to do", in the camera's terms; a `Rejected` error
//! keeps the raw `ER,<cmd>,<nn>` reply and says what the code means for that command (e.g.
//! `ER,PL,03`: the job does not exist on the camera). The core shows that text as it is
//! (`vision_core::VisionError::Driver`), and the typed [`KeyenceError`] travels inside the
//! [`vision_core::DriverError`] as its cause.
//!
//! A reading whose count says the camera found several marks is used, with a warning
//! ([`vision_core::CameraDriver::reading_warning`]) naming the mark the camera reported.
//!
//! # Never twice
//!
//! The connection is reused across calls and dropped after any failure except a camera
//! refusal. Before reuse the idle connection is probed (stale bytes drained, a closed
//! connection replaced) before anything is sent. Any failure after that is returned as it is,
//! and the next call reconnects: the driver never sends a command again on its own, so a `TRG`
//! the camera may have executed is never repeated.
//!
//! # Decisions where the spec is open
//!
//! * `TRG`'s answer is the line after the `TRG` echo; lines before the echo (a stale data
//!   output, an `ER` for another command) answer no command of ours and are skipped, counted
//!   against the 8-line bound. Every line after the echo is the data line.
//! * Range checks (|x|, |y|, width, height ≤ 10⁶ px, |angle| ≤ 360°, |score| ≤ 10⁶, count ≤
//!   10⁶) apply to readings that claim a mark; an NG or count-0 reading keeps whatever finite
//!   numbers the camera sent (cameras report sentinels when they find nothing). Exponents,
//!   `inf` and `NaN` are always malformed.
//! * Job switch: `PL,d,nnn` (job as three digits), `PW,d,nnn` after `ER,PL,01`; the command that
//!   worked is remembered. `d` is the device `PR` reports unless [`KeyenceConfig::memory_device`]
//!   is set. Job numbers above 999 are refused before connecting.
//! * Capabilities: `select_job` and `grab_image` (the camera FTP-pushes images; the driver
//!   picks the trigger's up from `VisionImageWatchDir`), as SPEC §7 lists.
//! * `test_connection` returns the text after `FVR,`.
//!
//! # Protocol facts: confirmed and assumed
//!
//! Confirmed by the manual seeds and by public client code for Keyence VS and CV-X cameras:
//! commands and replies end in CR; `TRG` is echoed as `TRG`, then the Data Output line follows
//! as its own line (possibly in the same segment); errors are `ER,<cmd>,<nn>` with codes 01–07;
//! the VS switches jobs with `PL,<device>,<job>` (devices 1 and 2); CV-X uses `PW,<device>,<job>`
//! answered by a bare `PW`; `PR` answers `PR,<device>,<job>`; `RUN` and `SET` switch Run/Setup
//! mode and `MOR` answers `MOR,1` in Run mode, `MOR,0` in Setup mode.
//!
//! Assumed (no primary Keyence document at hand): `PL` is acknowledged by a bare `PL`; `FVR`
//! answers `FVR,<version>`; IV-series `PW` takes the same `d,nnn` arguments as CV-X; `TRG` in
//! Setup mode answers `06` (SPEC) rather than `01` (one line of the manual); the camera's 3 s
//! command timeout counts from the command's first byte; a command over 500 bytes answers `02`;
//! a second client is accepted then reset (the manual says "refused"); the order in which the
//! emulator checks arguments (count, type, range, mode, busy).

mod config;
mod driver;
#[cfg(feature = "emulator")]
pub mod emulator;
mod error;
mod images;
mod protocol;
pub mod settings;
mod transport;

pub use config::{ImageWatch, KeyenceConfig, DEFAULT_PORT, DEFAULT_TIMEOUT, MAX_TIMEOUT};
pub use driver::{register, KeyenceDriver, DRIVER_NAME};
pub use error::{er_meaning, KeyenceError};
pub use protocol::{parse_data_line, Exchange, JobCommand, Limits, Program};
