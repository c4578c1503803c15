//! Depth pictures, as RGB-D cameras give them, and how they compare with the depth the
//! model predicts.

use crate::render::raster::Frame;

/// A depth picture: per pixel the depth along the camera's view direction (−ZCC, as the
/// renderer's depth images hold it), meters, or no reading. Rows top to bottom.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthImage {
    width: u32,
    height: u32,
    /// Meters; NaN where there is no reading.
    meters: Vec<f32>,
}

/// Why a depth picture was refused.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum DepthError {
    /// The samples do not fill the picture.
    #[error("a depth picture of {width}×{height} needs {expected} samples, not {got}")]
    Samples {
        width: u32,
        height: u32,
        expected: usize,
        got: usize,
    },
    /// The scale is not a positive number of meters per unit.
    #[error("the depth scale must be a positive number of meters per unit, not {0}")]
    Scale(f64),
}

impl DepthImage {
    /// A depth picture from 16-bit samples (row-major), each `scale` meters per unit;
    /// 0 is no reading.
    pub fn from_units(
        width: u32,
        height: u32,
        units: &[u16],
        scale: f64,
    ) -> Result<DepthImage, DepthError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(DepthError::Scale(scale));
        }
        let expected = width as usize * height as usize;
        if units.len() != expected {
            return Err(DepthError::Samples {
                width,
                height,
                expected,
                got: units.len(),
            });
        }
        let meters = units
            .iter()
            .map(|&u| {
                if u == 0 {
                    f32::NAN
                } else {
                    (u as f64 * scale) as f32
                }
            })
            .collect();
        Ok(DepthImage {
            width,
            height,
            meters,
        })
    }

    /// Width and height, pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The reading at pixel index `i` (row-major), meters; `None` for no reading.
    pub fn at(&self, i: usize) -> Option<f64> {
        self.meters
            .get(i)
            .filter(|m| m.is_finite())
            .map(|&m| m as f64)
    }
}

/// How a reading compares with the depth the model predicts at its pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reading {
    /// No reading.
    None,
    /// Within the tolerance of the prediction.
    Agrees,
    /// Nearer than the prediction by more than the tolerance (something the model does
    /// not have is in front), or a surface where the model predicts none.
    Nearer,
    /// Farther than the prediction by more than the tolerance (what the model predicts
    /// there is missing).
    Farther,
}

/// How near a reading must be to the prediction to agree: `absolute_m` plus `relative`
/// times the predicted depth (depth sensors' noise grows with distance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthTolerance {
    /// Meters.
    pub absolute_m: f64,
    /// A fraction of the predicted depth.
    pub relative: f64,
}

impl DepthTolerance {
    /// The reading at pixel `i` of `depth` against the model's `frame`.
    ///
    /// Precondition: the frame and the picture have the same size.
    pub fn compare(&self, depth: &DepthImage, frame: &Frame, i: usize) -> Reading {
        let Some(measured) = depth.at(i) else {
            return Reading::None;
        };
        let predicted = frame.depth.get(i).map_or(f64::INFINITY, |&d| d as f64);
        if !predicted.is_finite() {
            return Reading::Nearer;
        }
        let tolerance = self.absolute_m + self.relative * predicted;
        if measured < predicted - tolerance {
            Reading::Nearer
        } else if measured > predicted + tolerance {
            Reading::Farther
        } else {
            Reading::Agrees
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_become_meters_and_zero_is_no_reading() {
        let d = DepthImage::from_units(2, 1, &[0, 1500], 0.001).expect("a depth picture");
        assert_eq!(d.size(), (2, 1));
        assert_eq!(d.at(0), None);
        assert!((d.at(1).expect("a reading") - 1.5).abs() < 1e-6);
        assert_eq!(d.at(2), None);
    }

    #[test]
    fn a_bad_scale_or_sample_count_is_refused() {
        assert_eq!(
            DepthImage::from_units(2, 1, &[1, 2], 0.0),
            Err(DepthError::Scale(0.0))
        );
        assert!(DepthImage::from_units(2, 1, &[1, 2], f64::NAN).is_err());
        assert!(matches!(
            DepthImage::from_units(2, 2, &[1, 2], 0.001),
            Err(DepthError::Samples { expected: 4, .. })
        ));
    }

    #[test]
    fn readings_compare_with_the_prediction() {
        let frame = Frame {
            width: 4,
            height: 1,
            depth: vec![2.0, 2.0, 2.0, f32::INFINITY],
            face: vec![0, 0, 0, u32::MAX],
        };
        let depth = DepthImage::from_units(4, 1, &[2010, 1500, 2500, 3000], 0.001).expect("ok");
        let t = DepthTolerance {
            absolute_m: 0.02,
            relative: 0.01,
        };
        let got: Vec<Reading> = (0..4).map(|i| t.compare(&depth, &frame, i)).collect();
        assert_eq!(
            got,
            [
                Reading::Agrees,
                Reading::Nearer,
                Reading::Farther,
                Reading::Nearer
            ]
        );
    }
}
