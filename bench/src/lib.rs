//! ddastep virtual bench: the release firmware ELF on an emulated Blue Pill (`emu`), its
//! wall-clock serve mode for real G-code senders (`serve`), and benchmarks. The logic-analyzer
//! checker is its own crate (`bench/la`, `ddastep-la`), re-exported here as `la`.
pub use ddastep_la as la;
pub mod emu;
pub mod machine;
pub mod serve;
