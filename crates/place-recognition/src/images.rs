//! How any frame becomes an 8-bit image for the image-based methods (Khan 2017, §4.5.1):
//! a camera image is used as it is, a planar scan is rasterised ([`crate::rasterize_scan`]),
//! and a point cloud becomes its equirectangular intensity image `ⁱI` or range image `ʳI`
//! ([`crate::equirectangular`]).

use std::borrow::Cow;

use image::GrayImage;

use crate::{EquirectConfig, Frame, PlaceError, RasterConfig, Result, projection, raster};

/// Which lidar channel an image of a point cloud shows.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LidarChannel {
    /// Intensity (reflectivity) image.
    #[default]
    Intensity,
    /// Range image normalised by the maximum range.
    Range,
}

/// How frames become images.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageConfig {
    /// Planar scans.
    pub raster: RasterConfig,
    /// Point clouds.
    pub equirect: EquirectConfig,
    /// The channel of point-cloud images.
    pub channel: LidarChannel,
    /// Integer enlargement of every image (bilinear), at least 1. Default 1. Tiny camera
    /// images (Nordland's 64 × 32 px) need it for the feature stages: a keypoint needs its
    /// whole 31-pixel patch inside the image (see [`crate::FeatureConfig::patch_size`]).
    pub upscale: u32,
}

impl Default for ImageConfig {
    fn default() -> Self {
        Self {
            raster: RasterConfig::default(),
            equirect: EquirectConfig::default(),
            channel: LidarChannel::default(),
            upscale: 1,
        }
    }
}

impl ImageConfig {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        if self.upscale == 0 {
            return Err(PlaceError::InvalidParameter {
                name: "upscale",
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }

    /// The smallest integer enlargement that gives an image of `width × height` a shorter side
    /// of at least `min_side` pixels (1 when it already has; for an empty image, 1).
    pub fn upscale_for(width: u32, height: u32, min_side: u32) -> u32 {
        let side = width.min(height);
        if side == 0 || side >= min_side {
            1
        } else {
            min_side.div_ceil(side)
        }
    }
}

/// The image of a frame: the image itself, a rasterised planar scan, or an equirectangular
/// image of a cloud; enlarged [`ImageConfig::upscale`] times (bilinear).
pub fn frame_image<'a>(frame: &Frame<'a>, config: &ImageConfig) -> Result<Cow<'a, GrayImage>> {
    config.validate()?;
    let image = plain_image(frame, config)?;
    if config.upscale == 1 {
        return Ok(image);
    }
    let (w, h) = image.dimensions();
    Ok(Cow::Owned(image::imageops::resize(
        image.as_ref(),
        w.saturating_mul(config.upscale),
        h.saturating_mul(config.upscale),
        image::imageops::FilterType::Triangle,
    )))
}

fn plain_image<'a>(frame: &Frame<'a>, config: &ImageConfig) -> Result<Cow<'a, GrayImage>> {
    match *frame {
        Frame::Image(image) => Ok(Cow::Borrowed(image)),
        Frame::Planar(scan) => Ok(Cow::Owned(raster::rasterize_scan(scan, &config.raster)?)),
        Frame::Cloud(cloud) => {
            let images = projection::equirectangular(cloud, &config.equirect)?;
            Ok(Cow::Owned(match config.channel {
                LidarChannel::Intensity => images.intensity,
                LidarChannel::Range => images.range,
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn upscale_enlarges_and_keeps_constant_images_constant() {
        let image = GrayImage::from_pixel(8, 4, image::Luma([77]));
        let config = ImageConfig {
            upscale: 4,
            ..ImageConfig::default()
        };
        let big = frame_image(&Frame::Image(&image), &config).expect("image");
        assert_eq!(big.dimensions(), (32, 16));
        assert!(big.pixels().all(|p| p.0[0] == 77));
        let same = frame_image(&Frame::Image(&image), &ImageConfig::default()).expect("image");
        assert!(matches!(same, Cow::Borrowed(_)));
        let zero = ImageConfig {
            upscale: 0,
            ..ImageConfig::default()
        };
        assert!(frame_image(&Frame::Image(&image), &zero).is_err());
    }

    #[test]
    fn upscale_for_reaches_the_smallest_side() {
        assert_eq!(ImageConfig::upscale_for(64, 32, 128), 4);
        assert_eq!(ImageConfig::upscale_for(64, 33, 128), 4);
        assert_eq!(ImageConfig::upscale_for(640, 480, 128), 1);
        assert_eq!(ImageConfig::upscale_for(0, 0, 128), 1);
    }
}
