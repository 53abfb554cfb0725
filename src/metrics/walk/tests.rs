//! Tests of `walk`.

use super::*;
use crate::terrain::GroundFrame;
use glam::DVec3;

/// A foot on a 30° slope moving 0.2 m/s in its plane slides 0.2 mm in a 1 ms step while it
/// touches the ground, loaded or not; the loaded share counts none once its force is clamped
/// at zero (lifting off, or chattering in mid-stance).
#[test]
fn a_contact_slides_whole_and_its_loaded_share_apart() {
    let normal = DVec3::new(-0.5, 0.0, 0.75f64.sqrt());
    let contact = |normal_force| ContactForce {
        point: DVec3::ZERO,
        force: normal * normal_force,
        normal_force,
        friction: DVec3::ZERO,
        penetration: 1e-4,
        normal_velocity: 0.1,
        slip: DVec3::new(0.75f64.sqrt(), 0.0, 0.5) * 0.2,
        sticking: false,
        frame: GroundFrame::from_normal(normal),
        load: normal_force,
    };
    let (whole, loaded) = slid(&contact(5.0), 1e-3);
    assert!((whole - 2e-4).abs() < 1e-15);
    assert_eq!(loaded, whole);
    let (whole, loaded) = slid(&contact(0.0), 1e-3);
    assert!((whole - 2e-4).abs() < 1e-15);
    assert_eq!(loaded, 0.0);
}

/// Skating is a share of the distance commanded: a robot marking time (cluster/test's long
/// walks: 0.2 m of foot slip while the body wandered 0.06 m in 150 s) is not flagged, the
/// same slip on a walk commanded forward is.
#[test]
fn marking_time_is_not_skating() {
    let judged = |moving: bool| {
        let mut m = HexapodMetrics::new(1e-3, 2.5, Vec::new(), None);
        m.foot_slip = [0.218, 0.1, 0.1, 0.1, 0.1, 0.1];
        m.distance = 0.059;
        m.forward_distance = 0.059;
        m.command_progress = 0.059;
        m.acc.moving = moving;
        m.judge();
        m.walk_flags
    };
    assert_eq!(judged(false), Vec::<String>::new());
    let flags = judged(true);
    assert!(
        flags.len() == 1 && flags[0].starts_with("skated"),
        "{flags:?}"
    );
}

/// A turn commanded and not followed is flagged: less than half of it, or the other way; a walk
/// commanded to turn less than `HEADING_BOUND_DEG` in all is not judged on it.
#[test]
fn a_turn_not_followed_is_flagged() {
    let judged = |commanded_deg: f64, turned_deg: f64| {
        let mut m = HexapodMetrics::new(1e-3, 2.5, Vec::new(), None);
        m.acc.turning = true;
        m.acc.yaw_commanded = commanded_deg.to_radians();
        m.heading_change_deg = turned_deg;
        m.judge();
        m.walk_flags
    };
    assert_eq!(judged(100.0, 90.4), Vec::<String>::new());
    assert_eq!(judged(-100.0, -51.0), Vec::<String>::new());
    assert_eq!(judged(8.0, 0.0), Vec::<String>::new());
    for (commanded, turned) in [
        (1800.0, 162.0),
        (-1800.0, -162.0),
        (100.0, -20.0),
        (30.0, 0.0),
    ] {
        let flags = judged(commanded, turned);
        assert!(
            flags.len() == 1
                && flags[0].starts_with(&format!(
                    "turned {turned:+.1}° of the {commanded:+.1}° commanded"
                )),
            "{commanded}, {turned}: {flags:?}"
        );
    }
}

/// A swing brushing the ground is a scuff, not skating: the share is judged on the slip left
/// when the swings' scuffs are taken out (hex18 blind over 6 cm obstacles: 10.1 % of its
/// distance in contact, 3.5 % on the ground).
#[test]
fn a_swings_scuffs_are_not_skating() {
    let judged = |scuff: f64| {
        let mut m = HexapodMetrics::new(1e-3, 2.5, Vec::new(), None);
        m.foot_slip = [0.3, 0.1, 0.1, 0.1, 0.1, 0.1];
        m.foot_scuff = [scuff, 0.0, 0.0, 0.0, 0.0, 0.0];
        m.distance = 2.0;
        m.forward_distance = 2.0;
        m.command_progress = 2.0;
        m.acc.moving = true;
        m.judge();
        (m.slip_share.unwrap(), m.walk_flags)
    };
    let (share, flags) = judged(0.0);
    assert!(
        (share - 0.15).abs() < 1e-12 && flags.len() == 1,
        "{share} {flags:?}"
    );
    let (share, flags) = judged(0.2);
    // the worst foot on the ground is now another one, at 0.1 m
    assert!(
        (share - 0.05).abs() < 1e-12 && flags.is_empty(),
        "{share} {flags:?}"
    );
}

/// The fall test without the arc cosine answers as the tilt compared with the threshold does:
/// upright, tilted either side of 45° by a hair and far, upside down, and degenerate.
#[test]
fn the_fall_test_is_the_tilt_against_the_threshold() {
    let mut cases = vec![
        glam::DMat3::IDENTITY,
        glam::DMat3::from_diagonal(DVec3::splat(-1.0)),
    ];
    for k in 0..2000 {
        let angle = FALL_TILT + (k as f64 - 1000.0) * 1e-6 + if k % 7 == 0 { 1e-17 } else { 0.0 };
        cases.push(glam::DMat3::from_rotation_x(angle));
        cases.push(glam::DMat3::from_rotation_y(k as f64 * 0.0031) * 1.7);
    }
    cases.push(glam::DMat3::from_cols(DVec3::X, DVec3::Y, DVec3::ZERO));
    cases.push(glam::DMat3::from_cols(
        DVec3::X,
        DVec3::Y,
        DVec3::splat(f64::NAN),
    ));
    for body in &cases {
        assert_eq!(fallen(body), tilt(body) > FALL_TILT, "{body:?}");
    }
}

/// The largest tilt noted is the arc cosine of the least cosine noted, bit for bit (what
/// `note_attitude` keeps, `update` converting it): the arc cosine and the conversion to degrees
/// never turn a smaller cosine into a smaller tilt, over every cosine a body gives and past it
/// (clamped), NaN left out by both.
#[test]
fn the_largest_tilt_is_the_least_cosines() {
    let mut next = crate::test_rng::uniform(0x9e37_79b9_7f4a_7c15);
    // cosines over the whole range, and neighbouring floats near ±1, −0.3 and cos 45°
    let mut cosines: Vec<f64> = (0..200_000)
        .map(|k| -1.2 + 2.4 * k as f64 / 200_000.0)
        .collect();
    for start in [-1.0f64, -0.3, std::f64::consts::FRAC_1_SQRT_2, 1.0] {
        let mut c = start - 1e-12;
        for _ in 0..20_000 {
            cosines.push(c);
            c = c.next_up();
        }
    }
    cosines.sort_by(f64::total_cmp);
    let degrees = |c: f64| tilt_of(c).to_degrees();
    for pair in cosines.windows(2) {
        assert!(degrees(pair[0]) >= degrees(pair[1]), "{pair:?}");
    }
    for run in 0..2000 {
        let n = 1 + run % 50;
        let walk: Vec<f64> = (0..n)
            .map(|k| match (run + k) % 97 {
                0 => f64::NAN,
                1 => -0.0,
                _ => 1.0 - 2.2 * next().powi(1 + run % 5),
            })
            .collect();
        let by_tilts = walk.iter().fold(0.0f64, |max, &c| max.max(degrees(c)));
        let least = walk.iter().fold(None, |least: Option<f64>, &c| {
            Some(least.map_or(c, |l| l.min(c)))
        });
        let by_least = least.map_or(0.0, |c| 0.0f64.max(degrees(c)));
        assert_eq!(by_tilts.to_bits(), by_least.to_bits(), "{walk:?}");
    }
}
