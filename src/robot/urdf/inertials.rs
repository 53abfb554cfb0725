//! Inertials: each link's checked, merged bodies' summed (parallel axes), and the robot's judged —
//! refused where no rigid body could be so (placeholder inertials), warned where units look wrong.

use super::{plural, pose};
use crate::robot::model::{Link, RobotModel};
use glam::{DMat3, DVec3};

pub(super) fn check_inertial(link: &urdf_rs::Link) -> Result<(f64, DVec3, DMat3), String> {
    let i = &link.inertial;
    let mass = i.mass.value;
    if !mass.is_finite() || mass < 0.0 {
        return Err(format!(
            "link `{}`: <mass value> must be a finite number ≥ 0, got {mass}",
            link.name
        ));
    }
    let t = &i.inertia;
    let values = [t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    if values.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "link `{}`: <inertia> has a non-finite entry",
            link.name
        ));
    }
    let local = DMat3::from_cols_array(&[
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    ]);
    let frame = pose(&i.origin);
    let rotation = frame.matrix3;
    Ok((
        mass,
        frame.translation,
        rotation * local * rotation.transpose(),
    ))
}

/// The principal moments (ascending) of an inertia tensor no rigid body can have: the two smaller
/// sum to less than the largest (A + B ≥ C holds for any mass distribution, since
/// A + B − C = 2∫z² dm about the principal axes). None if the tensor is physical, to a relative
/// 10⁻⁶ that forgives rounding in a URDF's digits (a rod or a disc sits on the bound exactly).
fn impossible_inertia(m: &DMat3) -> Option<[f64; 3]> {
    use rapier3d::na;
    let a = m.to_cols_array();
    let mut moments: Vec<f64> = na::Matrix3::from_column_slice(&a)
        .symmetric_eigenvalues()
        .iter()
        .copied()
        .collect();
    moments.sort_by(f64::total_cmp);
    let [a, b, c] = [moments[0], moments[1], moments[2]];
    (a + b < c * (1.0 - 1e-6)).then_some([a, b, c])
}

fn positive_definite(m: &DMat3) -> bool {
    let a = m.to_cols_array_2d();
    let minor1 = a[0][0];
    let minor2 = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    minor1 > 0.0 && minor2 > 0.0 && m.determinant() > 0.0
}

/// Whether a URDF link carries neither mass nor inertia (no `<inertial>`: a frame, a passive
/// foot's).
pub(super) fn massless(link: &urdf_rs::Link) -> bool {
    let i = &link.inertial.inertia;
    link.inertial.mass.value == 0.0
        && [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz]
            .iter()
            .all(|&v| v == 0.0)
}

/// Every body needs a mass and a positive-definite inertia; a URDF with none at all is a
/// description for drawing, and is refused as such rather than by its first link. A body whose
/// tensor is singular because its URDF links are point masses (`point_masses`: name and mass,
/// every moment zero) is refused naming that cause, not only the merged tensor it leads to; when
/// at least [`PLACEHOLDER_COUNT`] of them state one and the same mass, that is said too: parts of
/// a real robot do not all weigh the same to the last digit (Lynxmotion's LSS hexapod gives 38
/// brackets, plates and feet 0.355132365146695 kg each, 13.5 kg of a robot its servos hold at 1.4
/// N·m), a placeholder copied from link to link.
pub(super) fn check_masses(links: &[Link], point_masses: &[(String, f64)]) -> Result<(), String> {
    if links.iter().all(|l| l.mass <= 0.0) {
        return Err(
            "no link has a mass: the URDF has no <inertial> elements (a description for drawing, as RViz reads it); hexsim needs each link's <mass> and <inertia>".into(),
        );
    }
    if links.iter().all(|l| l.inertia == DMat3::ZERO) {
        return Err(
            "no link states an inertia (every <inertia> is zero or missing); hexsim needs each link's inertia tensor (kg·m²)".into(),
        );
    }
    for link in links {
        if link.mass <= 0.0 {
            return Err(format!(
                "link `{}`: mass must be > 0 (a link moved by a joint needs inertia; give it an <inertial>)",
                link.name
            ));
        }
        if !positive_definite(&link.inertia) {
            let cause = if point_masses.is_empty() {
                String::new()
            } else {
                let shown: Vec<&str> = point_masses
                    .iter()
                    .take(4)
                    .map(|(name, _)| name.as_str())
                    .collect();
                format!(
                    "; the URDF gives {} link{} a mass but a zero inertia tensor (ixx = iyy = izz = 0: {}{}), point masses that cannot turn{}: give each link its inertia (kg·m²)",
                    point_masses.len(),
                    plural(point_masses.len()),
                    shown.join(", "),
                    if point_masses.len() > 4 { ", …" } else { "" },
                    placeholder_mass(point_masses)
                        .map(|mass| format!(
                            " (every one of them states the same {}: placeholder inertials?)",
                            weight(mass)
                        ))
                        .unwrap_or_default()
                )
            };
            return Err(format!(
                "link `{}`: the inertia tensor is not positive definite ({:?}){cause}",
                link.name,
                link.inertia.to_cols_array()
            ));
        }
    }
    Ok(())
}

/// At least this many point-mass links of one and the same mass read as a placeholder.
pub const PLACEHOLDER_COUNT: usize = 3;

/// The mass every point-mass link states, if there are [`PLACEHOLDER_COUNT`] or more of them and
/// they all state the same (to a relative 10⁻⁹: a value copied, not measured).
fn placeholder_mass(point_masses: &[(String, f64)]) -> Option<f64> {
    let (_, first) = point_masses.first()?;
    (point_masses.len() >= PLACEHOLDER_COUNT
        && point_masses
            .iter()
            .all(|(_, m)| (m - first).abs() <= 1e-9 * first))
    .then_some(*first)
}

/// A mass as a person reads it: grams under 0.1 kg, else kilograms.
fn weight(mass: f64) -> String {
    if mass < 0.1 {
        format!("{:.2} g", mass * 1e3)
    } else {
        format!("{mass:.3} kg")
    }
}

/// One warning naming the bodies whose principal moments break the triangle inequality.
pub(super) fn impossible_inertia_warning(links: &[Link]) -> Option<String> {
    let impossible: Vec<(&str, [f64; 3])> = links
        .iter()
        .filter_map(|l| Some((l.name.as_str(), impossible_inertia(&l.inertia)?)))
        .collect();
    let (first, [a, b, c]) = impossible.first()?;
    let others: Vec<&str> = impossible[1..].iter().map(|(name, _)| *name).collect();
    let more = if others.is_empty() {
        String::new()
    } else {
        format!(", and so do {} more: {}", others.len(), others.join(", "))
    };
    Some(format!(
        "link `{first}`: principal moments of inertia {a:.3e}, {b:.3e}, {c:.3e} kg·m² break \
         A + B ≥ C, which no rigid body can (MuJoCo refuses such a link unless told to \
         balance it){more}; simulated as given"
    ))
}

/// The robot's size D (m): the diagonal of the box around its joints and feet, standing at zero.
fn size(model: &RobotModel) -> f64 {
    let poses = model.link_poses(&vec![0.0; model.joints.len()]);
    let mut points: Vec<DVec3> = poses.iter().map(|p| p.translation).collect();
    points.extend(
        model
            .legs
            .iter()
            .map(|leg| poses[leg.foot_link].transform_point3(leg.foot.center)),
    );
    let low = points.iter().copied().fold(DVec3::INFINITY, DVec3::min);
    let high = points.iter().copied().fold(DVec3::NEG_INFINITY, DVec3::max);
    (high - low).length()
}

/// The least mass per cubic metre of its size D a robot is taken to be built with (kg/m³): the
/// 20 public hexapods of `tests/data/third_party` and hex18 have 1.2–25 (WORMS 1.6, arrg 1.2,
/// phobos 25), ten times this. A robot of a tenth of that is a URDF whose lengths and masses
/// disagree: found so, a robot of 0.23 kg spanning 5.6 m whose right femur joint stood on the
/// body's left (0.0013), and a Fusion 360 export whose joint origins held the children's world
/// positions, legs 3 m long on a 0.9 m body (0.011). Both walked, with no word.
pub const LEAST_DENSITY: f64 = 0.1;

/// Warns about a robot too light for its size ([`LEAST_DENSITY`]): its mass over D³.
pub(super) fn warn_implausible_density(model: &mut RobotModel) {
    let (size, mass) = (size(model), model.total_mass());
    let density = mass / size.powi(3);
    if size.is_finite() && size > 0.0 && density < LEAST_DENSITY {
        model.warnings.push(format!(
            "the robot weighs {} and spans {size:.3} m (its joints and feet, its joints at zero): {density:.2e} kg per cubic metre of its span, where built hexapods have 1–25 (hexsim's public robots): its lengths and masses disagree — joint origins given in the world frame (an exploded CAD export), lengths in another unit than metres, or masses left out? Simulated as given",
            weight(mass)
        ));
    }
}

/// A link's radius of gyration k = √(I_max/m) (its mass's spread about its centre) against the
/// robot's size D (the diagonal of the box around its joints and feet, standing at zero): no
/// part of a robot has k > D, and k < 0.5 % of D is a mass far denser than any material — the
/// marks of an inertia in g·mm² or kg·mm², or a mass in grams, where URDF wants kg·m² and kg
/// (hex18's links: 2–5 % of D). One warning per kind, naming the links; simulated as given.
/// A link whose k passes [`IMPOSSIBLE_SPREAD`]·D is refused: its inertia is more than 100 times
/// what its mass allows inside the robot (placeholder inertials: 10 mg links of 1 kg·m²).
pub(super) fn warn_implausible_inertias(model: &mut RobotModel) -> Result<(), String> {
    let size = size(model);
    if !(size.is_finite() && size > 0.0) {
        return Ok(());
    }
    let gyration = |l: &Link| {
        let largest = l
            .inertia
            .x_axis
            .x
            .max(l.inertia.y_axis.y)
            .max(l.inertia.z_axis.z);
        (largest / l.mass).sqrt()
    };
    let (mut wide, mut dense) = (Vec::new(), Vec::new());
    for link in &model.links {
        let k = gyration(link);
        if k > size {
            wide.push((link.name.clone(), k));
        } else if k < 0.005 * size {
            dense.push((link.name.clone(), k));
        }
    }
    let named = |links: &[(String, f64)]| {
        let more = links.len() - 1;
        let others = if more > 0 {
            format!(" (and {more} more link{})", plural(more))
        } else {
            String::new()
        };
        (links[0].0.clone(), links[0].1, others)
    };
    if let Some((name, k)) = wide
        .iter()
        .filter(|(_, k)| *k > IMPOSSIBLE_SPREAD * size)
        .max_by(|a, b| a.1.total_cmp(&b.1))
    {
        let weighs = weight(model.total_mass());
        let ratio = (k / size).powi(2);
        let count = wide
            .iter()
            .filter(|(_, k)| *k > IMPOSSIBLE_SPREAD * size)
            .count();
        let others = if count > 1 {
            format!(" (and {} more link{})", count - 1, plural(count - 1))
        } else {
            String::new()
        };
        return Err(format!(
            "the robot weighs {weighs}, and link `{name}`{others} has an inertia {ratio:.0e} times what its mass allows: it spreads its mass {k:.3} m from its centre (√(I/m)), the whole robot is {size:.3} m across — placeholder inertials, or an inertia in kg·mm² instead of kg·m²? No rigid body can be so; give each link its mass (kg) and inertia (kg·m²)"
        ));
    }
    if !wide.is_empty() {
        let (name, k, others) = named(&wide);
        model.warnings.push(format!(
            "link `{name}`{others}: its inertia spreads its mass {k:.3} m from its centre, more than the whole robot's {size:.3} m: an inertia in g·mm² or kg·mm² instead of kg·m²? Simulated as given"
        ));
    }
    if !dense.is_empty() {
        let (name, k, others) = named(&dense);
        model.warnings.push(format!(
            "link `{name}`{others}: its inertia spreads its mass only {:.2} mm from its centre, under 0.5 % of the robot's {size:.3} m (denser than any material): a mass in grams instead of kg? Simulated as given",
            k * 1e3
        ));
    }
    Ok(())
}

/// A link's radius of gyration beyond this many times the robot's size is refused (see
/// [`warn_implausible_inertias`]); between 1 and this it is warned about (the PhantomX's
/// placeholder inertias spread 3.6 times its size, and it walks).
pub const IMPOSSIBLE_SPREAD: f64 = 10.0;

/// Adds a point mass distribution (mass at `com` with `inertia` about it, all in the body frame)
/// to a body: combined centre of mass, parallel-axis theorem for the inertia.
pub(super) fn add_mass(body: &mut Link, mass: f64, com: DVec3, inertia: DMat3) {
    if mass <= 0.0 {
        return;
    }
    let total = body.mass + mass;
    let new_com = (body.com * body.mass + com * mass) / total;
    let shift =
        |m: f64, d: DVec3| DMat3::from_diagonal(DVec3::splat(d.dot(d))) * m - outer(d, d) * m;
    body.inertia =
        body.inertia + shift(body.mass, body.com - new_com) + inertia + shift(mass, com - new_com);
    body.mass = total;
    body.com = new_com;
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A solid box's inertia is physical; a thin disc sits on A + B = C and passes; a tensor whose
    /// two smaller moments fall short of the largest is flagged, however it is turned.
    #[test]
    fn inertias_no_rigid_body_can_have_are_flagged() {
        let (m, x, y, z) = (2.0, 0.3, 0.2, 0.1);
        let solid = DMat3::from_diagonal(
            DVec3::new(y * y + z * z, x * x + z * z, x * x + y * y) * m / 12.0,
        );
        assert_eq!(impossible_inertia(&solid), None);
        let r: f64 = 0.1;
        let disc = DMat3::from_diagonal(DVec3::new(0.25, 0.25, 0.5) * m * r * r);
        assert_eq!(impossible_inertia(&disc), None);
        let turn = DMat3::from_euler(glam::EulerRot::ZYX, 0.4, -0.7, 1.1);
        let bad = DMat3::from_diagonal(DVec3::new(1.0, 2.0, 3.5));
        let found = impossible_inertia(&(turn * bad * turn.transpose())).unwrap();
        for (got, want) in found.iter().zip([1.0, 2.0, 3.5]) {
            assert!((got - want).abs() < 1e-9, "{found:?}");
        }
        assert_eq!(impossible_inertia(&(turn * solid * turn.transpose())), None);
    }
}
