//! vision-grbl's integration tests: the emulator held to Grbl's protocol, the sender against
//! the emulator (whole programs and line by line), and the parsers on arbitrary bytes.

mod emulator;
mod parsers;
mod push;
mod sender;
