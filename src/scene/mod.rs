//! Tree files: the RON format users edit, its validation and its round trip.

pub mod value;

pub use value::{Dir3, Finite, NonNegative, P2, P3, Positive, Unit};
