//! The command-line applications on the library's public API: `render` and `profile` (commands/), `reference`,
//! `compare`, `bench` (with its report), `view` (the windowed viewer), `temporal` and the hidden `soak`.

pub mod bench;
pub mod bench_report;
pub mod commands;
pub mod compare;
pub mod flags;
pub mod heap;
pub mod profiler;
pub mod reference_cmd;
pub mod soak;
pub mod temporal;
pub mod viewer;
