//! Tests of the entry points against the in-test fakes.

mod alignment;
mod calibration;
mod fakes;
mod guards;
mod persistence;
mod record;
