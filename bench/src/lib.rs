//! ddastep virtual bench (placeholder until the modules land).
pub mod la;
pub mod emu;
