use std::collections::BTreeSet;

use super::*;

/// An L-shaped 300 m path with poles every 12 m on both sides, 4–6 m off, and one pole on the
/// path (0.5 m off).
fn small_config() -> SemiNcltConfig {
    let mut path: Vec<Point2<f64>> = (0..=300)
        .map(|i| Point2::new(i as f64 * 0.5, 0.0))
        .collect();
    path.extend((1..=300).map(|i| Point2::new(150.0, i as f64 * 0.5)));
    let mut poles = Vec::new();
    for k in 0..12 {
        let a = 6.0 + 12.0 * k as f64;
        poles.push(Point2::new(a, 4.0 + 0.1 * k as f64));
        poles.push(Point2::new(a + 3.0, -5.0));
        poles.push(Point2::new(155.0, a));
    }
    poles.push(Point2::new(60.0, 0.5));
    let mut config = SemiNcltConfig::new(path, poles);
    config.sessions = ["2012-01-08", "2012-08-20", "2013-02-23"]
        .map(String::from)
        .to_vec();
    config.scans_per_session = 40;
    config.firings = 90;
    config.construction_zones_per_km = 10.0;
    // Frequent changes so that a few sessions show each kind.
    config.changes.sign_post_removal = 0.3;
    config.changes.tree_removal = 0.3;
    config.changes.sign_post_move = 0.3;
    config.changes.new_sign_posts = 0.3;
    config
}

fn bits(cloud: &PointCloud) -> Vec<[u32; 3]> {
    cloud
        .points
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

#[test]
fn deterministic_by_seed_and_scan_index() {
    let a = SemiNclt::new(small_config(), 7).unwrap();
    let b = SemiNclt::new(small_config(), 7).unwrap();
    let c = SemiNclt::new(small_config(), 8).unwrap();
    let (sa, sb, sc) = (
        a.session(1).unwrap(),
        b.session(1).unwrap(),
        c.session(1).unwrap(),
    );
    assert_eq!(sa.ground_truth, sb.ground_truth);
    assert_eq!(sa.odometry, sb.odometry);
    assert_eq!(sa.odometry_std, sb.odometry_std);
    assert_ne!(sa.odometry, sc.odometry);
    // The same scan whatever the order of simulation; another index draws other noise.
    let late = bits(&sa.scan(5).unwrap());
    let _ = sb.scan(4).unwrap();
    assert_eq!(late, bits(&sb.scan(5).unwrap()));
    assert_eq!(late, bits(&(sa.scan_fn())(5).unwrap()));
    let cloud = sa.scan(5).unwrap();
    assert_eq!((cloud.height, cloud.width), (32, 90));
    assert!(cloud.num_valid() > cloud.len() / 3, "{}", cloud.num_valid());
    assert!(sa.scan(40).is_err());
}

#[test]
fn poles_are_the_real_ones_minus_those_on_the_path() {
    let config = small_config();
    let campus = SemiNclt::new(config.clone(), 3).unwrap();
    assert_eq!(campus.poles_on_path, vec![config.poles.len() - 1]);
    let (world, _) = campus.world(0).unwrap();
    assert_eq!(world.poles.len(), config.poles.len() - 1);
    for p in &world.poles {
        let input = config.poles[p.pole.id as usize];
        assert_eq!((p.pole.x, p.pole.y), (input.x, input.y));
    }
    // The first session's true poles are the placed ones.
    let session = campus.session(0).unwrap();
    assert_eq!(session.poles, world.pole_list());
}

#[test]
fn session_changes_accumulate() {
    let config = small_config();
    let campus = SemiNclt::new(config.clone(), 11).unwrap();
    let ids = |k: usize| -> BTreeSet<u32> {
        let (world, _) = campus.world(k).unwrap();
        world.poles.iter().map(|p| p.pole.id).collect()
    };
    let (first, second, third) = (ids(0), ids(1), ids(2));
    let (w1, log1) = campus.world(1).unwrap();
    let (w2, log2) = campus.world(2).unwrap();
    assert!(!log1.removed.is_empty() || !log2.removed.is_empty());
    for id in log1.removed.iter().chain(&log2.removed) {
        assert!(!third.contains(id), "removed pole {id} came back");
    }
    for id in &log1.removed {
        assert!(first.contains(id) && !second.contains(id));
    }
    for id in &log1.added {
        assert!(!first.contains(id) && second.contains(id));
    }
    // Foliage by month, cars redrawn, barrels in the construction zones.
    let (w0, log0) = campus.world(0).unwrap();
    assert_eq!((log0.foliage, log1.foliage, log2.foliage), (0.6, 1.0, 0.6));
    assert!(campus.parking_slots > 10 && campus.construction_zones > 0);
    assert_ne!(w0.cars, w1.cars);
    assert!(!w0.barrels.is_empty());
    assert_ne!(w0.barrels, w2.barrels);
}

#[test]
fn windows_overlap_and_odometry_follows_the_truth() {
    let config = small_config();
    let campus = SemiNclt::new(config.clone(), 5).unwrap();
    let w = 39.0 * 0.75;
    for k in 0..3 {
        let session = campus.session(k).unwrap();
        assert_eq!(session.len(), 40);
        let (start, end) = session.window_m;
        assert!((start - k as f64 * 0.25 * w).abs() < 1e-9 && (end - start - w).abs() < 1e-9);
        let gt = &session.ground_truth;
        let first = gt[0].translation();
        let p = campus.path().at(start);
        assert!((first.x - p.x).abs() < 1e-9 && (first.y - p.y).abs() < 1e-9);
        assert!((first.z - 1.5).abs() < 1e-12);
        for i in 1..session.len() {
            let step = (gt[i].translation() - gt[i - 1].translation()).norm();
            assert!((step - 0.75).abs() < 0.01, "step {step}");
            let truth = gt[i - 1].to_planar().inverse() * gt[i].to_planar();
            let odo =
                session.odometry[i - 1].to_planar().inverse() * session.odometry[i].to_planar();
            let std = session.odometry_std[i];
            assert!(std.iter().all(|s| *s > 0.0) && std[0] < 0.01);
            assert!((odo.x() - truth.x()).abs() < 6.0 * std[0] + 1e-3);
            assert!((session.stamps_secs[i] - session.stamps_secs[i - 1] - 0.1).abs() < 1e-6);
        }
    }
}

#[test]
fn bad_parameters_are_errors() {
    let mut config = small_config();
    config.scans_per_session = 0;
    assert!(SemiNclt::new(config, 1).is_err());
    let mut config = small_config();
    config.sessions = vec!["2012-13-01".into()];
    assert!(SemiNclt::new(config, 1).is_err());
    let mut config = small_config();
    config.poles.push(Point2::new(f64::NAN, 0.0));
    assert!(SemiNclt::new(config, 1).is_err());
    let campus = SemiNclt::new(small_config(), 1).unwrap();
    assert!(campus.session(3).is_err());
}

#[test]
fn real_nclt_layout_and_path() {
    if raypath_io::data::require("nclt-poles/ground-truth-poles.csv").is_none() {
        return;
    }
    let config = SemiNcltConfig::from_data_dir().unwrap();
    assert_eq!(config.poles.len(), 1205);
    assert_eq!(config.path.len(), 12_999);
    let path = ArcPath::new(&config.path).unwrap();
    assert!(
        (path.length_m() - 6469.6).abs() < 1.0,
        "{}",
        path.length_m()
    );
    let mut config = config;
    config.sessions.truncate(1);
    config.scans_per_session = 2;
    let campus = SemiNclt::new(config.clone(), 1).unwrap();
    let (world, _) = campus.world(0).unwrap();
    // Every real pole is placed at its real position, except those on the path.
    let on_path = campus.poles_on_path.len();
    assert!(on_path < 60, "{on_path} poles within 1 m of the path");
    assert_eq!(world.poles.len() + on_path, 1205);
    for p in &world.poles {
        let input = config.poles[p.pole.id as usize];
        assert_eq!((p.pole.x, p.pole.y), (input.x, input.y));
    }
    eprintln!(
        "{on_path} of 1205 poles within 1 m of the path; {} parking slots, {} construction zones",
        campus.parking_slots, campus.construction_zones
    );
}
