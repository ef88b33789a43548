//! How any frame becomes an 8-bit image for the image-based methods (Khan 2017, §4.5.1):
//! a camera image is used as it is, a planar scan is rasterised ([`crate::rasterize_scan`]),
//! and a point cloud becomes its equirectangular intensity image `ⁱI` or range image `ʳI`
//! ([`crate::equirectangular`]).

use std::borrow::Cow;

use image::GrayImage;

use crate::{EquirectConfig, Frame, RasterConfig, Result, projection, raster};

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
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImageConfig {
    /// Planar scans.
    pub raster: RasterConfig,
    /// Point clouds.
    pub equirect: EquirectConfig,
    /// The channel of point-cloud images.
    pub channel: LidarChannel,
}

/// The image of a frame: the image itself, a rasterised planar scan, or an equirectangular
/// image of a cloud.
pub fn frame_image<'a>(frame: &Frame<'a>, config: &ImageConfig) -> Result<Cow<'a, GrayImage>> {
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
