//! vision-grbl's integration tests: the emitter against the emulator and the interpreter, the
//! emulator held to Grbl's protocol, the sender against the emulator (whole programs and line
//! by line), and the parsers on arbitrary bytes.

mod emit;
mod emit_chain;
mod emulator;
mod parsers;
mod push;
mod sender;
