//! Tests of the entry points against the in-test fakes.

mod alignment;
mod fakes;
mod guards;
