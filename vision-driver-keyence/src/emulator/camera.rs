//! The emulated camera's command interpreter, free of sockets and threads.

use std::time::Instant;

use super::settings::{EmulatorSettings, Mode, Series};
use super::source::{ResultSource, Shot};
use crate::protocol::{Program, MAX_COMMAND_LEN};

/// What the camera answers to one command.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Answer {
    /// Nothing (an empty command).
    Nothing,
    /// One reply line, without delimiter.
    Line(String),
    /// `TRG` was accepted: the echo, then the shot.
    Trigger(Shot),
}

/// The camera's state and its result source.
pub(crate) struct Camera {
    pub(crate) settings: EmulatorSettings,
    pub(crate) mode: Mode,
    pub(crate) program: Program,
    busy_until: Option<Instant>,
    source: Box<dyn ResultSource>,
}

impl Camera {
    pub(crate) fn new(settings: EmulatorSettings, source: Box<dyn ResultSource>) -> Camera {
        let (device, job) = settings.program;
        Camera { mode: settings.mode, program: Program { device, job }, busy_until: None, source, settings }
    }

    /// Answers one complete command (without its delimiter) received at `now`.
    pub(crate) fn handle(&mut self, command: &[u8], now: Instant) -> Answer {
        if command.is_empty() {
            return Answer::Nothing;
        }
        let text = String::from_utf8_lossy(command);
        let mut fields = text.split(',');
        let name = fields.next().unwrap_or("");
        let args: Vec<&str> = fields.collect();
        let er = |code: u8| Answer::Line(format!("ER,{},{code:02}", command_name(command)));
        let busy = self.busy_until.is_some_and(|t| now < t);
        let job_command = match self.settings.series {
            Series::Vs => "PL",
            Series::CvX => "PW",
        };
        match name {
            "FVR" | "MOR" | "RUN" | "SET" | "TRG" | "PR" if !args.is_empty() => er(2),
            "FVR" => Answer::Line(format!("FVR,{}", self.settings.version)),
            "MOR" => Answer::Line(format!("MOR,{}", u8::from(self.mode == Mode::Run))),
            "RUN" | "SET" if busy => er(5),
            "RUN" => {
                self.mode = Mode::Run;
                Answer::Line("RUN".into())
            }
            "SET" => {
                self.mode = Mode::Setup;
                Answer::Line("SET".into())
            }
            "TRG" | "PR" if self.mode == Mode::Setup => er(6),
            "TRG" | "PR" if busy => er(5),
            "TRG" => Answer::Trigger(self.source.trigger()),
            "PR" => Answer::Line(format!("PR,{},{:03}", self.program.device, self.program.job)),
            n if n == job_command => self.load(&args, now, busy).map_or_else(er, |()| Answer::Line(n.to_string())),
            _ => er(1),
        }
    }

    fn load(&mut self, args: &[&str], now: Instant, busy: bool) -> Result<(), u8> {
        let [device, job] = args else { return Err(2) };
        let number = |s: &str| -> Result<u32, u8> {
            if s.is_empty() || s.len() > 4 || !s.bytes().all(|b| b.is_ascii_digit()) {
                return Err(4);
            }
            s.parse().map_err(|_| 4)
        };
        let (device, job) = (number(device)?, number(job)?);
        if !(1..=2).contains(&device) || job > self.settings.max_job {
            return Err(3);
        }
        if self.mode == Mode::Setup {
            return Err(6);
        }
        if busy {
            return Err(5);
        }
        self.source.select_job(job)?;
        self.program = Program { device: u8::try_from(device).map_err(|_| 3)?, job };
        if !self.settings.load_time.is_zero() {
            self.busy_until = Some(now + self.settings.load_time);
        }
        Ok(())
    }
}

/// A command's name as the camera quotes it in `ER,<name>,<nn>`: the text before the first
/// comma, letters and digits only, at most 8.
pub(crate) fn command_name(command: &[u8]) -> String {
    command
        .iter()
        .take_while(|&&b| b != b',')
        .filter(|b| b.is_ascii_alphanumeric())
        .take(8)
        .map(|&b| char::from(b))
        .collect()
}

/// The answer to a command cut off by the command timeout (`07`) or longer than the camera
/// accepts (`02`, assumed: the manual does not say).
pub(crate) fn refusal(command: &[u8], code: u8) -> String {
    debug_assert!(command.len() <= MAX_COMMAND_LEN);
    format!("ER,{},{code:02}", command_name(command))
}

#[cfg(test)]
mod tests {
    use super::super::source::ListSource;
    use super::*;
    use std::time::Duration;
    use vision_core::Reading;

    fn camera(settings: EmulatorSettings) -> Camera {
        Camera::new(settings, Box::new(ListSource::readings([Reading::position(1.0, 2.0)])))
    }

    fn line(a: Answer) -> String {
        match a {
            Answer::Line(l) => l,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn commands_and_their_errors() {
        let now = Instant::now();
        let mut c = camera(EmulatorSettings { max_job: 50, ..EmulatorSettings::default() });
        assert_eq!(c.handle(b"", now), Answer::Nothing);
        assert_eq!(c.handle(b"TRG", now), Answer::Trigger(Shot::Reading(Reading::position(1.0, 2.0))));
        assert!(line(c.handle(b"FVR", now)).starts_with("FVR,1.00"));
        assert_eq!(line(c.handle(b"MOR", now)), "MOR,1");
        assert_eq!(line(c.handle(b"PR", now)), "PR,1,000");
        assert_eq!(line(c.handle(b"PL,2,7", now)), "PL");
        assert_eq!(line(c.handle(b"PR", now)), "PR,2,007");
        for (cmd, reply) in [
            (&b"XYZ"[..], "ER,XYZ,01"),
            (b"trg", "ER,trg,01"),
            (b"PW,1,5", "ER,PW,01"),
            (b"TRG,1", "ER,TRG,02"),
            (b"FVR,1", "ER,FVR,02"),
            (b"PL,1", "ER,PL,02"),
            (b"PL,1,2,3", "ER,PL,02"),
            (b"PL,1,x", "ER,PL,04"),
            (b"PL,a,1", "ER,PL,04"),
            (b"PL,3,1", "ER,PL,03"),
            (b"PL,1,51", "ER,PL,03"),
            (b"\xff\x00", "ER,,01"),
        ] {
            assert_eq!(line(c.handle(cmd, now)), reply, "{}", String::from_utf8_lossy(cmd));
        }
    }

    #[test]
    fn setup_mode_refuses_inspection_commands() {
        let now = Instant::now();
        let mut c = camera(EmulatorSettings::default());
        assert_eq!(line(c.handle(b"SET", now)), "SET");
        assert_eq!(line(c.handle(b"MOR", now)), "MOR,0");
        assert_eq!(line(c.handle(b"TRG", now)), "ER,TRG,06");
        assert_eq!(line(c.handle(b"PR", now)), "ER,PR,06");
        assert_eq!(line(c.handle(b"PL,1,1", now)), "ER,PL,06");
        assert!(line(c.handle(b"FVR", now)).starts_with("FVR,"));
        assert_eq!(line(c.handle(b"RUN", now)), "RUN");
        assert!(matches!(c.handle(b"TRG", now), Answer::Trigger(_)));
    }

    #[test]
    fn loading_a_job_makes_the_camera_busy() {
        let now = Instant::now();
        let load = Duration::from_millis(100);
        let mut c = camera(EmulatorSettings { load_time: load, series: Series::CvX, ..EmulatorSettings::default() });
        assert_eq!(line(c.handle(b"PL,1,1", now)), "ER,PL,01");
        assert_eq!(line(c.handle(b"PW,1,3", now)), "PW");
        assert_eq!(line(c.handle(b"TRG", now)), "ER,TRG,05");
        assert_eq!(line(c.handle(b"PW,1,4", now)), "ER,PW,05");
        assert!(line(c.handle(b"MOR", now)).starts_with("MOR"));
        assert!(matches!(c.handle(b"TRG", now + load), Answer::Trigger(_)));
    }

    #[test]
    fn refusals_name_the_command() {
        assert_eq!(refusal(b"TR", 7), "ER,TR,07");
        assert_eq!(refusal(b"PL,1,00", 7), "ER,PL,07");
        assert_eq!(command_name(b"ABCDEFGHIJ"), "ABCDEFGH");
    }
}
