//! ddastep virtual bench (placeholder until the modules land).
