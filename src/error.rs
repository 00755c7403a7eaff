//! The one error type of the core: what is wrong with the data a caller handed in.

use core::fmt;

/// What is wrong with a scene, a budget or a setting handed to the core.
///
/// Every variant names the offending quantity (`what`) so that a front end can
/// prefix it with a location (the scene-file parser adds the JSON path).
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A number is NaN or infinite.
    NotFinite {
        /// The quantity.
        what: &'static str,
    },
    /// A length, size or count must be positive.
    NotPositive {
        /// The quantity.
        what: &'static str,
        /// The value received.
        value: f32,
    },
    /// A value lies outside its allowed range.
    OutOfRange {
        /// The quantity.
        what: &'static str,
        /// The value received.
        value: f32,
        /// Smallest allowed value.
        min: f32,
        /// Largest allowed value.
        max: f32,
    },
    /// A direction has zero length, or two directions are parallel where they must not be.
    Degenerate {
        /// The quantity.
        what: &'static str,
    },
    /// More items were requested than the compiled capacity holds.
    Capacity {
        /// The budgeted item.
        what: &'static str,
        /// How many were requested.
        requested: usize,
        /// The compiled capacity.
        capacity: usize,
    },
    /// A size derived from the input is too large to count (a grid side beyond `u32`).
    TooLarge {
        /// The quantity.
        what: &'static str,
        /// The size derived.
        value: f32,
    },
    /// A combination of settings that this code path does not support.
    Unsupported {
        /// The combination.
        what: &'static str,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::NotFinite { what } => write!(f, "{what} must be a finite number"),
            Error::NotPositive { what, value } => {
                write!(f, "{what} must be positive (got {value})")
            }
            Error::OutOfRange {
                what,
                value,
                min,
                max,
            } => {
                write!(f, "{what} must lie in [{min}, {max}] (got {value})")
            }
            Error::Degenerate { what } => {
                write!(f, "{what} is degenerate (zero length or parallel)")
            }
            Error::Capacity {
                what,
                requested,
                capacity,
            } => write!(
                f,
                "{what}: {requested} requested but the compiled capacity is {capacity}"
            ),
            Error::TooLarge { what, value } => write!(f, "{what}: {value} is too large to count"),
            Error::Unsupported { what } => write!(f, "{what} are not supported"),
        }
    }
}

#[cfg(feature = "std")]
#[cfg_attr(docsrs, doc(cfg(feature = "std")))]
impl std::error::Error for Error {}

/// `Ok(x)` when `x` is finite.
pub(crate) fn finite(x: f32, what: &'static str) -> Result<f32, Error> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(Error::NotFinite { what })
    }
}

/// `Ok(x)` when `x` is finite and strictly positive.
pub(crate) fn positive(x: f32, what: &'static str) -> Result<f32, Error> {
    if finite(x, what)? > 0.0 {
        Ok(x)
    } else {
        Err(Error::NotPositive { what, value: x })
    }
}

/// `Ok(requested)` when `requested` items fit into `capacity`, else
/// [`Error::Capacity`] naming `what`.
pub(crate) fn within(
    requested: usize,
    capacity: usize,
    what: &'static str,
) -> Result<usize, Error> {
    if requested <= capacity {
        Ok(requested)
    } else {
        Err(Error::Capacity {
            what,
            requested,
            capacity,
        })
    }
}

/// `Ok(x)` when `x` is finite and in `[min, max]`.
pub(crate) fn in_range(x: f32, min: f32, max: f32, what: &'static str) -> Result<f32, Error> {
    if finite(x, what)? >= min && x <= max {
        Ok(x)
    } else {
        Err(Error::OutOfRange {
            what,
            value: x,
            min,
            max,
        })
    }
}
