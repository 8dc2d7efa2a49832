//! [`ProgramHandler`]: M280–M284 of a program on the simulated machine, through a [`Session`].

use vision_core::Controller;
use vision_gcode::{Context, HandlerError, MCodeHandler, UserMCode};
use vision_mcode::Outcome;

use crate::machine::{Clock, ContextMachine};

use crate::error::HostError;
use crate::session::Session;

/// One Vision M-code as it ran.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The program line.
    pub line: u32,
    /// The M number.
    pub mcode: u32,
    /// What it did, or why it was refused (the operator's message).
    pub result: Result<Outcome, HostError>,
}

impl Record {
    /// The alignment G-code this record's M282 emitted (the `G10`/`G52`/`G68`/`G51` lines), or
    /// `None` when the record is no successful M282.
    #[must_use]
    pub fn applied_gcode(&self) -> Option<&[String]> {
        match &self.result {
            Ok(Outcome::Apply(reply)) => Some(&reply.gcode),
            _ => None,
        }
    }
}

/// The most [`Record`]s a handler keeps between two [`ProgramHandler::take_records`]: a program
/// of millions of Vision M-codes keeps its memory bounded; the rest are only counted
/// ([`ProgramHandler::records_dropped`]).
pub const MAX_RECORDS: usize = 10_000;

/// The interpreter's handler for M280–M284: each call runs through the [`Session`] on the
/// interpreter as a machine of `controller` ([`ContextMachine`]) — the path every bridge runs —
/// and a [`Record`] of it is kept for reports. A refused call stops the program at its line with
/// the module's message.
pub struct ProgramHandler {
    session: Session,
    controller: &'static dyn Controller,
    clock: Clock,
    records: Vec<Record>,
    /// Calls past [`MAX_RECORDS`] since the last [`ProgramHandler::take_records`], not kept.
    records_dropped: u64,
}

impl std::fmt::Debug for ProgramHandler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ProgramHandler")
            .field("session", &self.session)
            .field("controller", &self.controller.name())
            .field("records", &self.records)
            .finish()
    }
}

impl ProgramHandler {
    /// A handler running `session` on an interpreter that is a `controller`, telling time by
    /// `clock`.
    #[must_use]
    pub fn new(session: Session, controller: &'static dyn Controller, clock: Clock) -> ProgramHandler {
        ProgramHandler { session, controller, clock, records: Vec::new(), records_dropped: 0 }
    }

    /// The session.
    #[must_use]
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// The session, mutably.
    pub fn session_mut(&mut self) -> &mut Session {
        &mut self.session
    }

    /// The controller the interpreter is.
    #[must_use]
    pub fn controller(&self) -> &'static dyn Controller {
        self.controller
    }

    /// The clock.
    #[must_use]
    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    /// Every call since the last take, in order (the first [`MAX_RECORDS`]).
    #[must_use]
    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// Takes the records, leaving none and resetting [`ProgramHandler::records_dropped`].
    pub fn take_records(&mut self) -> Vec<Record> {
        self.records_dropped = 0;
        std::mem::take(&mut self.records)
    }

    /// Calls since the last [`ProgramHandler::take_records`] that were not kept.
    #[must_use]
    pub fn records_dropped(&self) -> u64 {
        self.records_dropped
    }

    /// Runs one Vision M-code on the interpreter behind `ctx`.
    ///
    /// # Errors
    /// The parse, the module's refusal or the machine's failure (also recorded).
    pub fn dispatch(&mut self, mcode: u32, words: &[(char, f64)], ctx: &mut Context<'_>) -> Result<Outcome, HostError> {
        let line = ctx.line();
        let mut machine = ContextMachine::new(ctx, &self.clock, self.controller);
        let result = self.session.mcode(&mut machine, mcode, words);
        if self.records.len() < MAX_RECORDS {
            self.records.push(Record { line, mcode, result: result.clone() });
        } else {
            self.records_dropped += 1;
        }
        result
    }
}

impl MCodeHandler for ProgramHandler {
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
        match self.dispatch(call.code(), call.words(), ctx) {
            // The module ran its G-code on the interpreter already (`Context::execute`).
            Ok(_) => Ok(Vec::new()),
            Err(e) => Err(HandlerError::Failed(e.to_string())),
        }
    }
}
