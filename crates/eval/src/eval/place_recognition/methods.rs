//! The methods of the evaluation, built with their default parameters and boxed as
//! [`Runner`]s, and the offline DBoW2-style vocabularies.

use std::sync::Arc;

use anyhow::Result;
use image::GrayImage;
use raypath_place_recognition::{
    BinaryVocabulary, Bits512, Checked, Dbow, DbowConfig, FeatureConfig, GeometricCheck,
    GeometricCheckConfig, GistConfig, GlobalDescriptorDb, HogConfig, Ibuild, IbuildConfig,
    IbuildScore, ImageConfig, PlaceError, PlanarDescriptors, PolarConfig, PolarContext,
    ScanContext, ScanContextConfig, ScanShapeConfig, Shot3dBow, Shot3dBowConfig, ShotConfig,
    VocabularyConfig, detect_and_describe,
};

use super::runner::{Features, Input, Runner, Sample, boxed, boxed_features, features_of};

/// Seed of vocabulary training.
pub const VOCABULARY_SEED: u64 = 2017;

/// Trains a vocabulary on the descriptors of some images (one list per image).
pub fn train_vocabulary(images: &[Vec<Bits512>]) -> Result<Arc<BinaryVocabulary>> {
    Ok(Arc::new(BinaryVocabulary::train(
        images,
        &VocabularyConfig::default(),
        VOCABULARY_SEED,
    )?))
}

/// The DBoW2-style baseline over a vocabulary, on the shared features of `input`.
pub fn dbow(vocabulary: &Arc<BinaryVocabulary>, input: Input) -> Box<dyn Runner> {
    fn describe(
        m: &mut Dbow,
        s: &Sample<'_>,
        input: Input,
    ) -> raypath_place_recognition::Result<(raypath_place_recognition::DbowDescription, f64)> {
        let f = features_of(s, input)?;
        Ok((
            m.describe_descriptors(f.keypoints.clone(), &f.descriptors),
            f.seconds,
        ))
    }
    boxed_features(
        Dbow::new(Arc::clone(vocabulary), DbowConfig::default()),
        "DBoW2-style",
        input,
        describe,
    )
}

/// Scan Context with its defaults (Kim & Kim 2018).
pub fn scan_context() -> Result<Box<dyn Runner>> {
    Ok(boxed(
        ScanContext::new(ScanContextConfig::default())?,
        "Scan Context",
        Input::Cloud,
    ))
}

/// The matching threshold δ of IBuILD's default (bits).
pub const DEFAULT_DELTA: u32 = 80;

/// IBuILD (β = 10; Khan 2017, §4.6.1) with matching threshold `delta`, on the shared features
/// of `input`. Labelled "IBuILD" at the default δ, "IBuILD δ=NN" otherwise.
pub fn ibuild(input: Input, delta: u32) -> Result<Box<dyn Runner>> {
    fn describe(
        m: &mut Ibuild,
        s: &Sample<'_>,
        input: Input,
    ) -> raypath_place_recognition::Result<(raypath_place_recognition::IbuildDescription, f64)>
    {
        let f = features_of(s, input)?;
        Ok((m.describe_descriptors(f.descriptors.clone()), f.seconds))
    }
    let label = if delta == DEFAULT_DELTA {
        "IBuILD".to_string()
    } else {
        format!("IBuILD δ={delta}")
    };
    Ok(boxed_features(
        Ibuild::new(IbuildConfig {
            delta,
            ..IbuildConfig::default()
        })?,
        label,
        input,
        describe,
    ))
}

/// IBuILD with our symmetric, unnormalised similarity (`IbuildScore::Symmetric`: the query's
/// old words missing from a hypothesis count like the hypothesis' missing words, and `S` is
/// not divided by `Σ_L S`), default δ. Labelled "Symmetric IBuILD (ours)".
pub fn ibuild_symmetric(input: Input) -> Result<Box<dyn Runner>> {
    fn describe(
        m: &mut Ibuild,
        s: &Sample<'_>,
        input: Input,
    ) -> raypath_place_recognition::Result<(raypath_place_recognition::IbuildDescription, f64)>
    {
        let f = features_of(s, input)?;
        Ok((m.describe_descriptors(f.descriptors.clone()), f.seconds))
    }
    Ok(boxed_features(
        Ibuild::new(IbuildConfig {
            delta: DEFAULT_DELTA,
            score: IbuildScore::Symmetric,
            ..IbuildConfig::default()
        })?,
        SYMMETRIC_IBUILD.to_string(),
        input,
        describe,
    ))
}

/// The label of [`ibuild_symmetric`].
pub const SYMMETRIC_IBUILD: &str = "Symmetric IBuILD (ours)";

/// The features of a planar scan: rasterised with [`raster`], then FAST/BRIEF-512.
pub fn planar_features(scan: &raypath_geometry::Scan2) -> Result<Features> {
    let started = std::time::Instant::now();
    let image = raypath_place_recognition::rasterize_scan(scan, &raster())?;
    Features::of(&image, started)
}

/// The raster of the 2-D logs: 0.1 m pixels over ±15 m (ours; the crate default is 0.05 m —
/// 301 × 301 instead of 601 × 601 pixels makes feature extraction about 4× faster).
pub fn raster() -> raypath_place_recognition::RasterConfig {
    raypath_place_recognition::RasterConfig {
        pixel_m: std::env::var("PLACE_RECOGNITION_PIXEL_M")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.1),
        ..raypath_place_recognition::RasterConfig::default()
    }
}

/// The planar polar-context baseline (Scan Context's polar grid on the 2-D end points).
pub fn polar() -> Result<Box<dyn Runner>> {
    Ok(boxed(
        PolarContext::new(PolarConfig::default())?,
        "polar context",
        Input::Planar,
    ))
}

/// HOG with its defaults, cosine similarity (Khan 2017, §4.5.2).
pub fn hog(input: Input) -> Box<dyn Runner> {
    boxed(
        GlobalDescriptorDb::hog(HogConfig::default(), ImageConfig::default()),
        "HOG",
        input,
    )
}

/// GIST with its defaults, cosine similarity (Khan 2017, §4.5.2).
pub fn gist(input: Input) -> Result<Box<dyn Runner>> {
    Ok(boxed(
        GlobalDescriptorDb::gist(GistConfig::default(), ImageConfig::default())?,
        "GIST",
        input,
    ))
}

/// SHOT bag of words on the cloud, with or without the intensity texture (ψ = 0.1 m).
pub fn shot(with_intensity: bool) -> Result<Box<dyn Runner>> {
    let config = Shot3dBowConfig {
        shot: ShotConfig {
            with_intensity,
            ..ShotConfig::default()
        },
        ..Shot3dBowConfig::default()
    };
    Ok(boxed(
        Shot3dBow::new(config)?,
        if with_intensity {
            "SHOT + intensity"
        } else {
            "SHOT"
        },
        Input::Cloud,
    ))
}

/// The suffix of a method's label with the geometric check.
pub const CHECKED: &str = " + geometric check";

/// The geometric check of the 2-D logs: the defaults, and in kidnapped mode no frame within
/// the ground truth's exclusion window is checked (such pairs are not scored).
fn check_config() -> GeometricCheckConfig {
    GeometricCheckConfig {
        exclude_recent: super::truth::MIN_GAP_FRAMES,
        ..GeometricCheckConfig::default()
    }
}

/// IBuILD (default δ, printed or symmetric score) with the geometric check on the planar scans.
fn ibuild_checked(score: IbuildScore, label: &str) -> Result<Box<dyn Runner>> {
    fn describe(
        m: &mut GeometricCheck<Ibuild>,
        s: &Sample<'_>,
        input: Input,
    ) -> raypath_place_recognition::Result<(
        Checked<raypath_place_recognition::IbuildDescription>,
        f64,
    )> {
        let f = features_of(s, input)?;
        let d = m.inner_mut().describe_descriptors(f.descriptors.clone());
        Ok((m.attach(d, planar_scan(s)?), f.seconds))
    }
    let ibuild = Ibuild::new(IbuildConfig {
        delta: DEFAULT_DELTA,
        score,
        ..IbuildConfig::default()
    })?;
    Ok(boxed_features(
        GeometricCheck::new(ibuild, check_config())?,
        format!("{label}{CHECKED}"),
        Input::Planar,
        describe,
    ))
}

/// The DBoW2-style baseline with the geometric check on the planar scans.
fn dbow_checked(vocabulary: &Arc<BinaryVocabulary>) -> Result<Box<dyn Runner>> {
    fn describe(
        m: &mut GeometricCheck<Dbow>,
        s: &Sample<'_>,
        input: Input,
    ) -> raypath_place_recognition::Result<(Checked<raypath_place_recognition::DbowDescription>, f64)>
    {
        let f = features_of(s, input)?;
        let d = m
            .inner_mut()
            .describe_descriptors(f.keypoints.clone(), &f.descriptors);
        Ok((m.attach(d, planar_scan(s)?), f.seconds))
    }
    let dbow = Dbow::new(Arc::clone(vocabulary), DbowConfig::default());
    Ok(boxed_features(
        GeometricCheck::new(dbow, check_config())?,
        format!("DBoW2-style{CHECKED}"),
        Input::Planar,
        describe,
    ))
}

/// The planar scan of a sample.
fn planar_scan<'a>(
    s: &Sample<'a>,
) -> raypath_place_recognition::Result<&'a raypath_geometry::Scan2> {
    match s.frame(Input::Planar) {
        Some(raypath_place_recognition::Frame::Planar(scan)) => Ok(scan),
        _ => Err(PlaceError::BadInput(
            "no planar scan for the geometric check".into(),
        )),
    }
}

/// IBuILD's matching threshold δ on binary shape descriptors made on the scan (bits; ours):
/// the library's choice, made on intel and freiburg-079 and fixed for every log.
pub use raypath_place_recognition::SHAPE_DELTA;
/// The δ sweep of the symmetric IBuILD on scan shapes (bits).
pub const SHAPE_DELTAS: [u32; 6] = [20, 25, 30, 35, 40, 50];
/// The label of IBuILD (printed score) on scan shapes.
pub const SHAPE_IBUILD: &str = "IBuILD on scan shapes (ours)";
/// The label of IBuILD (symmetric score) on scan shapes.
pub const SHAPE_SYMMETRIC: &str = "Symmetric IBuILD on scan shapes (ours)";

/// IBuILD on binary shape descriptors made on the planar scan (`PlanarDescriptors::Shape`,
/// default settings), printed or symmetric score, with or without the geometric check.
/// Labelled with " δ=NN" when `delta` is not [`SHAPE_DELTA`].
pub fn ibuild_shape(score: IbuildScore, delta: u32, checked: bool) -> Result<Box<dyn Runner>> {
    let config = IbuildConfig {
        delta,
        score,
        planar: PlanarDescriptors::Shape(ScanShapeConfig::default()),
        ..IbuildConfig::default()
    };
    let mut label = match score {
        IbuildScore::Printed => SHAPE_IBUILD,
        IbuildScore::Symmetric => SHAPE_SYMMETRIC,
    }
    .to_string();
    if delta != SHAPE_DELTA {
        label += &format!(" δ={delta}");
    }
    let ibuild = Ibuild::new(config)?;
    Ok(if checked {
        let check = GeometricCheck::new(ibuild, check_config())?;
        boxed(check, label + CHECKED, Input::Planar)
    } else {
        boxed(ibuild, label, Input::Planar)
    })
}

/// The methods of the real 2-D logs: IBuILD and DBoW2-style on rasterised scans, IBuILD on
/// scan shapes, planar polar context; each also with the geometric check; the δ sweeps.
pub fn planar(vocabulary: Option<&Arc<BinaryVocabulary>>) -> Result<Vec<Box<dyn Runner>>> {
    let mut out = vec![
        ibuild(Input::Planar, DEFAULT_DELTA)?,
        ibuild_symmetric(Input::Planar)?,
        polar()?,
        ibuild_checked(IbuildScore::default(), "IBuILD")?,
        ibuild_checked(IbuildScore::Symmetric, SYMMETRIC_IBUILD)?,
        boxed(
            GeometricCheck::new(PolarContext::new(PolarConfig::default())?, check_config())?,
            format!("polar context{CHECKED}"),
            Input::Planar,
        ),
    ];
    if let Some(v) = vocabulary {
        out.push(dbow(v, Input::Planar));
        out.push(dbow_checked(v)?);
    }
    for score in [IbuildScore::Printed, IbuildScore::Symmetric] {
        for checked in [false, true] {
            out.push(ibuild_shape(score, SHAPE_DELTA, checked)?);
        }
    }
    for delta in DELTAS {
        if delta != DEFAULT_DELTA {
            out.push(ibuild(Input::Planar, delta)?);
        }
    }
    for delta in SHAPE_DELTAS {
        if delta != SHAPE_DELTA {
            for checked in [false, true] {
                out.push(ibuild_shape(IbuildScore::Symmetric, delta, checked)?);
            }
        }
    }
    Ok(out)
}

/// Descriptors of an image for vocabulary training (3-D: intensity images).
pub fn image_descriptors(image: &GrayImage) -> Result<Vec<Bits512>> {
    Ok(detect_and_describe(image, &FeatureConfig::default())?.1)
}

/// The δ sweep of IBuILD (bits of 512): the thesis traces its precision–recall points by
/// varying δ (Khan 2017, §4.6.1) without printing the values.
pub const DELTAS: [u32; 5] = [50, 65, 80, 95, 110];

/// The methods of the 40 real KITTI frames.
pub fn kitti_real(
    vocabulary: Option<&Arc<BinaryVocabulary>>,
    with_shot: bool,
) -> Result<Vec<Box<dyn Runner>>> {
    let mut out = vec![scan_context()?];
    for input in [Input::Intensity, Input::Range] {
        out.push(hog(input));
        out.push(gist(input)?);
    }
    out.push(ibuild(Input::Intensity, DEFAULT_DELTA)?);
    out.push(ibuild_symmetric(Input::Intensity)?);
    if let Some(v) = vocabulary {
        out.push(dbow(v, Input::Intensity));
    }
    if with_shot {
        out.push(shot(false)?);
        out.push(shot(true)?);
    }
    Ok(out)
}

/// The methods of the semi-synthetic drives.
pub fn semi_kitti(vocabulary: Option<&Arc<BinaryVocabulary>>) -> Result<Vec<Box<dyn Runner>>> {
    let mut out = vec![scan_context()?];
    for input in [Input::Intensity, Input::Range, Input::Camera] {
        out.push(hog(input));
        out.push(gist(input)?);
        out.push(ibuild(input, DEFAULT_DELTA)?);
    }
    out.push(ibuild_symmetric(Input::Intensity)?);
    if let Some(v) = vocabulary {
        out.push(dbow(v, Input::Intensity));
    }
    for delta in DELTAS {
        if delta != DEFAULT_DELTA {
            out.push(ibuild(Input::Intensity, delta)?);
        }
    }
    Ok(out)
}

/// The DBoW2-style vocabulary of the 3-D sections: trained on intensity images of simulated
/// scans along sequence 03 (`kitti-poles/03`, a sequence neither 3-D section evaluates), every
/// `stride`-th frame. Returns it with a note for the report.
pub fn kitti_vocabulary(
    ctx: &crate::eval::EvalContext,
) -> Result<(Option<Arc<BinaryVocabulary>>, String)> {
    use rayon::prelude::*;
    use raypath_place_recognition::{EquirectConfig, equirectangular};
    use raypath_sim::semi_kitti::{SemiKittiConfig, SemiKittiDrive};
    let dir = ctx.data("kitti-poles/03");
    if !dir.join("poses.txt").exists() {
        return Ok((
            None,
            "`kitti-poles/03` missing: no DBoW2-style vocabulary for the 3-D sections.".into(),
        ));
    }
    let stride = if ctx.quick { 40 } else { 10 };
    let mut config = SemiKittiConfig::from_files(
        &dir.join("poses.txt"),
        &dir.join("times.txt"),
        &dir.join("poles.csv"),
    )?;
    config.sequence = "03".into();
    config.stride = stride;
    config.labels = false;
    let drive = SemiKittiDrive::new(&config, raypath_sim::datasets::DEFAULT_SEED)?;
    let images: Vec<Vec<Bits512>> = (0..drive.len())
        .into_par_iter()
        .map(|i| {
            let image = equirectangular(&drive.scan(i)?, &EquirectConfig::default())?.intensity;
            image_descriptors(&image)
        })
        .collect::<Result<_>>()?;
    let descriptors: usize = images.iter().map(Vec::len).sum();
    let vocabulary = train_vocabulary(&images)?;
    let note = format!(
        "DBoW2-style vocabulary of the 3-D sections: trained offline on the intensity images of \
         {} simulated scans along sequence 03 (every {stride}th frame; a sequence neither 3-D \
         section evaluates) — {descriptors} descriptors, {} words (k = 10, L = 6).",
        images.len(),
        vocabulary.word_count()
    );
    Ok((Some(vocabulary), note))
}
