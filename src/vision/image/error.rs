//! Why a picture, or what is asked of it, cannot be analysed.

/// Why an image operation was refused. Nothing was computed.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ImageError {
    /// Samples that are not 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA) bytes per
    /// pixel.
    #[error("an image must have 1 to 4 channels (got {channels})")]
    Channels {
        /// The channel count given.
        channels: u8,
    },
    /// A sample buffer that does not have width × height × channels entries.
    #[error("the image needs {expected} samples (width × height × channels), got {got}")]
    Samples {
        /// width × height × channels (`usize::MAX` when that overflows).
        expected: usize,
        /// The samples given.
        got: usize,
    },
    /// A size or an option out of its range (a zero width, a negative threshold).
    #[error("{what} is out of range (got {value})")]
    BadParameter {
        /// Which one.
        what: &'static str,
        /// Its value.
        value: f64,
    },
}
