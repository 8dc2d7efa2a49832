//! What the driver needs to reach a camera and keep its images, built from its settings
//! ([`crate::settings`]).

use std::path::PathBuf;
use std::time::Duration;

use vision_core::Params;

use crate::error::KeyenceError;
use crate::protocol::Limits;
use crate::settings;

/// The Keyence Non-Procedural port (SPEC §7).
pub const DEFAULT_PORT: u16 = 8500;
/// `VisionTimeout`'s default, 3 s.
pub const DEFAULT_TIMEOUT: Duration = Duration::from_secs(3);
/// Longest `VisionTimeout` the driver accepts, 300 s (the parameter's own bound).
pub const MAX_TIMEOUT: Duration = Duration::from_secs(300);

/// How to reach the camera and how long to wait for it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyenceConfig {
    /// Camera IP address or host name (`VisionIP`).
    pub ip: String,
    /// TCP port of the Non-Procedural command channel (`VisionPort`, Keyence default 8500).
    pub port: u16,
    /// Time allowed for one whole driver call (`VisionTimeout`): connecting when needed, sending
    /// the command and receiving the complete reply. Not per byte: a peer that dribbles bytes
    /// cannot stretch it.
    pub timeout: Duration,
    /// Bounds on reply lines.
    pub limits: Limits,
    /// Memory device for job switches (1 or 2); `None` keeps the device the camera reports with
    /// `PR` (default).
    pub memory_device: Option<u8>,
    /// Idle time before TCP keepalive probes start, so a camera that vanished while idle is
    /// noticed (default 10 s; `None` disables).
    pub keepalive: Option<Duration>,
    /// Where the camera pushes its images, for M281 D1.
    pub images: ImageWatch,
}

/// The folder a VS camera FTP-pushes its inspection images into, and how long M281 D1 waits
/// there for the trigger's image.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageWatch {
    /// The folder (`VisionImageWatchDir`); empty: no images are kept.
    pub dir: PathBuf,
    /// How long to wait for a fresh image (`VisionImageGrabTimeout`, default 2 s, at most 60 s).
    pub timeout: Duration,
}

impl Default for ImageWatch {
    /// No folder, 2 s.
    fn default() -> Self {
        ImageWatch { dir: PathBuf::new(), timeout: Duration::from_secs(2) }
    }
}

impl KeyenceConfig {
    /// A configuration for the camera at `ip:port` with the defaults: 3 s timeout, default
    /// [`Limits`], the camera's current memory device, keepalive after 10 s idle, no image
    /// folder.
    #[must_use]
    pub fn new(ip: impl Into<String>, port: u16) -> KeyenceConfig {
        KeyenceConfig {
            ip: ip.into(),
            port,
            timeout: DEFAULT_TIMEOUT,
            limits: Limits::default(),
            memory_device: None,
            keepalive: Some(Duration::from_secs(10)),
            images: ImageWatch::default(),
        }
    }

    /// The same configuration with `timeout`.
    #[must_use]
    pub fn with_timeout(mut self, timeout: Duration) -> KeyenceConfig {
        self.timeout = timeout;
        self
    }

    /// The driver's settings in `params` (`[keyence]`: `VisionIP`, `VisionPort`,
    /// `VisionTimeout`, `VisionImageWatchDir`, `VisionImageGrabTimeout`; their defaults when
    /// `params` has no such table), defaults for the rest.
    ///
    /// # Errors
    /// [`KeyenceError::Config`] naming the setting when a value is out of the driver's range.
    pub fn from_params(params: &Params) -> Result<KeyenceConfig, KeyenceError> {
        let table = settings::settings(params);
        // The table read each value as its type and checked its range when it was set.
        let text = |name: &str| table.text(name).ok_or_else(|| bad(format!("{name} is missing")));
        let seconds = |name: &str| {
            let s = table.float(name).ok_or_else(|| bad(format!("{name} is missing")))?;
            Duration::try_from_secs_f64(s).map_err(|_| bad(format!("{name} {s} s is not a duration")))
        };
        let port = table.int("VisionPort").ok_or_else(|| bad("VisionPort is missing".into()))?;
        let port = u16::try_from(port).map_err(|_| bad(format!("VisionPort {port} is not a TCP port")))?;
        let config = KeyenceConfig {
            timeout: seconds("VisionTimeout")?,
            images: ImageWatch {
                dir: PathBuf::from(text("VisionImageWatchDir")?),
                timeout: seconds("VisionImageGrabTimeout")?,
            },
            ..KeyenceConfig::new(text("VisionIP")?, port)
        };
        config.validate()?;
        Ok(config)
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`KeyenceError::Config`] naming the field.
    pub fn validate(&self) -> Result<(), KeyenceError> {
        let bad = |reason: String| Err(KeyenceError::Config { reason });
        if self.ip.trim().is_empty() {
            return bad("VisionIP is empty".into());
        }
        if !settings::PORT.accepts(&i64::from(self.port)) {
            return bad("VisionPort 0 is not a TCP port".into());
        }
        if !settings::TIMEOUT.accepts(&self.timeout.as_secs_f64()) {
            return bad(format!("VisionTimeout {:?} must be more than 0 and at most 300 s", self.timeout));
        }
        if let Some(d) = self.memory_device.filter(|d| !(1..=2).contains(d)) {
            return bad(format!("memory device {d} must be 1 or 2"));
        }
        if !settings::GRAB_TIMEOUT.accepts(&self.images.timeout.as_secs_f64()) {
            return bad(format!("VisionImageGrabTimeout {:?} must be at most 60 s", self.images.timeout));
        }
        if self.keepalive.is_some_and(|k| k < Duration::from_secs(1)) {
            return bad("keepalive must be at least 1 s".into());
        }
        self.limits.validate().or_else(bad)
    }

    /// `ip:port` for messages.
    #[must_use]
    pub fn address(&self) -> String {
        if self.ip.contains(':') {
            format!("[{}]:{}", self.ip, self.port)
        } else {
            format!("{}:{}", self.ip, self.port)
        }
    }
}

fn bad(reason: String) -> KeyenceError {
    KeyenceError::Config { reason }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_the_manual_defaults() {
        let c = KeyenceConfig::from_params(&Params::default()).expect("defaults");
        assert_eq!(c.ip, "192.168.208.80");
        assert_eq!(c.port, DEFAULT_PORT);
        assert_eq!(c.timeout, DEFAULT_TIMEOUT);
        assert_eq!(c.address(), "192.168.208.80:8500");
        assert_eq!(c.images, ImageWatch::default());
        let mut p = Params::default().with_driver_settings(&settings::SETTINGS);
        p.set("VisionTimeout", 0.25).expect("timeout");
        p.set("VisionIP", "camera-1").expect("ip");
        p.set("VisionPort", 8600).expect("port");
        p.set("VisionImageWatchDir", "/srv/ftp/vs").expect("folder");
        p.set("VisionImageGrabTimeout", "0.5").expect("grab timeout");
        let c = KeyenceConfig::from_params(&p).expect("set");
        assert_eq!((c.ip.as_str(), c.port, c.timeout), ("camera-1", 8600, Duration::from_millis(250)));
        assert_eq!(c.images, ImageWatch { dir: PathBuf::from("/srv/ftp/vs"), timeout: Duration::from_millis(500) });
    }

    #[test]
    fn every_field_is_checked() {
        let ok = KeyenceConfig::new("127.0.0.1", 8500);
        assert_eq!(ok.validate(), Ok(()));
        for bad in [
            KeyenceConfig { ip: " ".into(), ..ok.clone() },
            KeyenceConfig { port: 0, ..ok.clone() },
            ok.clone().with_timeout(Duration::ZERO),
            ok.clone().with_timeout(Duration::from_secs(301)),
            KeyenceConfig { memory_device: Some(3), ..ok.clone() },
            KeyenceConfig { keepalive: Some(Duration::from_millis(10)), ..ok.clone() },
            KeyenceConfig {
                images: ImageWatch { timeout: Duration::from_secs(61), ..ImageWatch::default() },
                ..ok.clone()
            },
            KeyenceConfig { limits: Limits { max_line_len: 4, max_lines: 8 }, ..ok.clone() },
        ] {
            assert!(matches!(bad.validate(), Err(KeyenceError::Config { .. })), "{bad:?}");
        }
        assert_eq!(KeyenceConfig::new("::1", 8500).address(), "[::1]:8500");
    }
}
