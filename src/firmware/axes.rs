//! How many axes the firmware drives (X Y Z A B C U): the size of the engine and the move ring.
//! A leaf, so the app and the handlers that need it do not import each other.

/// Axes the firmware drives.
pub const AXES: usize = ddastep::MAX_AXES;
