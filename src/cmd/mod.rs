//! The commands of the binary, one module per group, next to their clap
//! definitions (`cli`). The library (`anholonomy`) holds everything they
//! call; nothing here is needed by the Python package.

pub mod cli;
pub mod fit;
pub mod inspect;
pub mod logs;
pub mod margin;
pub mod progress;
pub mod run;
pub mod table;
