//! [`VisionHandler`]: M280–M284 plugged into the interpreter.

use vision_core::VisionModule;
use vision_gcode::{Context, HandlerError, MCodeHandler, UserMCode};

use crate::call::VisionCall;
use crate::error::McodeError;
use crate::machine::{Clock, ContextMachine};
use crate::outcome::Outcome;

/// One Vision M-code as it ran.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The program line.
    pub line: u32,
    /// The M number.
    pub mcode: u32,
    /// What it did, or why it was refused.
    pub result: Result<Outcome, McodeError>,
}

/// The interpreter's handler for M280–M284: parses the words, runs the Vision module on the
/// interpreter as its host ([`ContextMachine`]; the module runs its own G-code through it, in
/// place, at the M-code's line), and keeps a [`Record`] of every call for reports.
///
/// A refused call stops the program at its line with the module's message.
pub struct VisionHandler {
    module: VisionModule,
    clock: Clock,
    records: Vec<Record>,
    /// Calls past [`MAX_RECORDS`] since the last [`VisionHandler::take_records`], not kept.
    records_dropped: u64,
}

/// The most [`Record`]s a handler keeps between two [`VisionHandler::take_records`]: a program
/// of millions of Vision M-codes keeps its memory bounded; the rest are only counted
/// ([`VisionHandler::records_dropped`]).
pub const MAX_RECORDS: usize = 10_000;

impl std::fmt::Debug for VisionHandler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("VisionHandler").field("module", &self.module).field("records", &self.records).finish()
    }
}

impl VisionHandler {
    /// A handler around `module`, telling time by `clock`.
    #[must_use]
    pub fn new(module: VisionModule, clock: Clock) -> VisionHandler {
        VisionHandler { module, clock, records: Vec::new(), records_dropped: 0 }
    }

    /// The Vision module (parameters, dot list, driver).
    #[must_use]
    pub fn module(&self) -> &VisionModule {
        &self.module
    }

    /// The Vision module, mutably (e.g. to change a parameter between programs).
    pub fn module_mut(&mut self) -> &mut VisionModule {
        &mut self.module
    }

    /// The module, handing the handler back.
    #[must_use]
    pub fn into_module(self) -> VisionModule {
        self.module
    }

    /// The clock.
    #[must_use]
    pub fn clock(&self) -> &Clock {
        &self.clock
    }

    /// Every call so far, in order.
    #[must_use]
    pub fn records(&self) -> &[Record] {
        &self.records
    }

    /// Takes the records (the first [`MAX_RECORDS`] calls since the last take), leaving none
    /// and resetting [`VisionHandler::records_dropped`].
    pub fn take_records(&mut self) -> Vec<Record> {
        self.records_dropped = 0;
        std::mem::take(&mut self.records)
    }

    /// Calls since the last [`VisionHandler::take_records`] that were not kept (past
    /// [`MAX_RECORDS`]).
    #[must_use]
    pub fn records_dropped(&self) -> u64 {
        self.records_dropped
    }

    /// Runs one Vision M-code on the interpreter behind `ctx`.
    ///
    /// # Errors
    /// The parse or the module's refusal (also recorded).
    pub fn dispatch(
        &mut self,
        mcode: u32,
        words: &[(char, f64)],
        ctx: &mut Context<'_>,
    ) -> Result<Outcome, McodeError> {
        let line = ctx.line();
        let result = VisionCall::parse(mcode, words).and_then(|call| {
            let mut machine = ContextMachine::new(ctx, &self.clock);
            call.run(&mut self.module, &mut machine).map_err(McodeError::from)
        });
        if self.records.len() < MAX_RECORDS {
            self.records.push(Record { line, mcode, result: result.clone() });
        } else {
            self.records_dropped += 1;
        }
        result
    }
}

impl MCodeHandler for VisionHandler {
    fn call(&mut self, call: &UserMCode<'_>, ctx: &mut Context<'_>) -> Result<Vec<String>, HandlerError> {
        match self.dispatch(call.code(), call.words(), ctx) {
            // The module ran its G-code on the interpreter already (`Context::execute`).
            Ok(_) => Ok(Vec::new()),
            Err(e) => Err(HandlerError::Failed(e.to_string())),
        }
    }
}
