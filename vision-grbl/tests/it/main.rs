//! vision-grbl's integration tests: the emitter against the emulator and the interpreter, the emulator held to Grbl's protocol, the sender against
//! the emulator, and the parsers on arbitrary bytes.

mod emit;
mod emit_chain;
mod emulator;
mod parsers;
mod sender;
