//! Beam patterns of real rotating lidars: the elevation of every laser, by hardware laser id.
//!
//! * **Velodyne HDL-32E**: 32 lasers from −30.67° to +10.67° in steps of 4/3° (≈ 1.33°),
//!   fired in the interleaved order of the HDL-32E user manual (laser 0 at −30.67°, laser 1 at
//!   −9.33°, laser 2 at −29.33°, …), the values of Velodyne's `db.xml` as shipped with MRPT
//!   (`libs/obs/src/velodyne_default_calib_HDL-32.h`, BSD). NCLT used this sensor.
//! * **Velodyne HDL-64E S3**: the `vert_correction` values (radians) of a factory calibration
//!   in the ROS `velodyne_pointcloud` YAML format, as shipped with MRPT
//!   (`libs/obs/src/velodyne_default_calib_hdl64e-s3.h`, BSD). The upper block (lasers 0–31)
//!   spans +1.96° … −8.56°, the lower block (lasers 32–63) −8.77° … −24.56°: the irregular,
//!   unit-specific table a real sensor has, not the nominal +2° … −24.8° grid of the data
//!   sheet. KITTI used an HDL-64E (S2); its per-unit table is not published with the data, so
//!   this S3 table stands in for it.
//!
//! Firing counts per revolution at 10 Hz: the HDL-32E fires every 46.08 µs (≈ 21 700 firings/s,
//! 2170 per revolution, 0.166° apart); the HDL-64E S2/S3 delivers ≈ 1.33 M points/s over 64
//! lasers (≈ 20 833 firings/s, 2083 per revolution, 0.173° apart).
//!
//! The per-laser azimuth (`rot_correction`), distance and vertical-offset corrections of the
//! calibration are not modelled: every laser fires from the sensor origin along the column's
//! azimuth, the layout of a de-skewed, organized range image.

/// Firings per revolution of the HDL-32E at 10 Hz.
pub const HDL32E_FIRINGS_10HZ: usize = 2170;

/// Firings per revolution of the HDL-64E at 10 Hz.
pub const HDL64E_FIRINGS_10HZ: usize = 2083;

/// Maximum range of the HDL-32E in metres (data sheet: 80–100 m).
pub const HDL32E_MAX_RANGE_M: f64 = 100.0;

/// Maximum range of the HDL-64E in metres (data sheet: 120 m).
pub const HDL64E_MAX_RANGE_M: f64 = 120.0;

/// Elevation of every HDL-32E laser in degrees, indexed by hardware laser id.
pub const HDL32E_ELEVATIONS_DEG: [f64; 32] = [
    -30.67, -9.33, -29.33, -8.00, -28.00, -6.67, -26.67, -5.33, -25.33, -4.00, -24.00, -2.67,
    -22.67, -1.33, -21.33, 0.00, -20.00, 1.33, -18.67, 2.67, -17.33, 4.00, -16.00, 5.33, -14.67,
    6.67, -13.33, 8.00, -12.00, 9.33, -10.67, 10.67,
];

/// Elevation (`vert_correction`) of every HDL-64E S3 laser in radians, indexed by hardware
/// laser id (see the module documentation for the source).
pub const HDL64E_ELEVATIONS_RAD: [f64; 64] = [
    -0.126_181_845_529_289_8,
    -0.119_537_459_097_422_21,
    0.003_561_187_259_061_75,
    0.010_306_535_403_103_584,
    -0.114_496_744_014_140_1,
    -0.108_036_123_299_215_03,
    -0.149_445_381_017_024_26,
    -0.143_443_532_313_290_66,
    -0.102_780_167_231_259_98,
    -0.095_695_900_232_024_51,
    -0.138_634_520_160_186_3,
    -0.131_810_736_570_493_97,
    -0.054_438_932_963_427_306,
    -0.048_730_533_448_148_504,
    -0.089_615_953_280_251_92,
    -0.083_935_330_680_018_6,
    -0.043_427_018_903_405_855,
    -0.036_488_012_167_155_39,
    -0.079_061_879_225_601_39,
    -0.072_558_140_151_505_77,
    -0.031_587_736_747_464_255,
    -0.025_460_288_914_769_372,
    -0.066_658_784_162_766_27,
    -0.060_551_128_363_789_01,
    0.015_620_435_355_027_301,
    0.022_567_997_346_205_196,
    -0.019_943_931_467_746_017,
    -0.013_200_099_491_225_388,
    0.027_266_617_424_120_905,
    0.034_210_146_308_463_29,
    -0.007_885_903_531_460_533,
    -0.001_549_189_150_655_206_7,
    -0.390_212_162_047_557_43,
    -0.383_550_187_932_817_53,
    -0.197_138_848_550_284,
    -0.187_685_796_255_632_28,
    -0.375_083_665_544_563_1,
    -0.367_628_823_257_227_23,
    -0.428_566_871_917_561_6,
    -0.421_441_076_554_104_2,
    -0.356_545_511_268_165_2,
    -0.347_178_608_425_391_94,
    -0.411_010_203_546_022_7,
    -0.400_830_308_884_377_93,
    -0.284_031_583_797_270_9,
    -0.277_615_334_587_919_26,
    -0.335_926_872_163_512_4,
    -0.330_267_519_890_873_16,
    -0.268_517_107_730_198_05,
    -0.260_518_543_020_988_37,
    -0.321_645_174_507_000_7,
    -0.313_528_067_034_995_6,
    -0.249_416_782_901_732_72,
    -0.240_952_511_988_213_4,
    -0.303_135_137_484_852_43,
    -0.293_236_345_552_533_86,
    -0.177_604_634_869_772_88,
    -0.170_069_268_326_737_74,
    -0.229_741_215_005_102_64,
    -0.223_918_918_793_497_18,
    -0.162_315_290_568_244_04,
    -0.153_144_246_828_800_32,
    -0.214_571_197_119_203_36,
    -0.207_926_676_296_983_4,
];

/// The HDL-32E elevations in radians by laser id.
pub fn hdl32e_elevations_rad() -> Vec<f64> {
    HDL32E_ELEVATIONS_DEG
        .iter()
        .map(|deg| deg.to_radians())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hdl32e_is_a_regular_grid_of_four_thirds_degree() {
        let mut sorted = HDL32E_ELEVATIONS_DEG;
        sorted.sort_by(f64::total_cmp);
        for (k, e) in sorted.iter().enumerate() {
            let nominal = (k as f64 - 23.0) * 4.0 / 3.0;
            assert!((e - nominal).abs() < 0.006, "{k}: {e} vs {nominal}");
        }
    }

    #[test]
    fn hdl64e_blocks_span_the_published_ranges() {
        let deg: Vec<f64> = HDL64E_ELEVATIONS_RAD
            .iter()
            .map(|r| r.to_degrees())
            .collect();
        let (upper, lower) = deg.split_at(32);
        let max = |v: &[f64]| v.iter().copied().fold(f64::MIN, f64::max);
        let min = |v: &[f64]| v.iter().copied().fold(f64::MAX, f64::min);
        assert!((max(upper) - 2.0).abs() < 0.1 && (min(upper) + 8.5).abs() < 0.2);
        assert!((max(lower) + 8.8).abs() < 0.1 && (min(lower) + 24.6).abs() < 0.3);
        assert!(min(upper) > max(lower) - 0.3);
    }
}
