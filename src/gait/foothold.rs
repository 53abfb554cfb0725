//! Footholds away from edges (perceptive: the terrain is known).
//!
//! A foot planned to land next to a riser's edge, a stone's rim or a trench's lip stands half on
//! nothing, slips off the edge or stubs the riser, and one landing on the edge itself is where
//! the contact is stiffest. Where the ground under a foothold's footprint has an edge, the
//! foothold moves along the leg's direction of travel to the nearest point whose footprint is
//! edge-free — onto the tread — no farther than the stride allows. The choice is made once per
//! swing, for where the foot will land, and held: chosen afresh each step it would flip from one
//! tread to the next as the body carries the planned point across an edge, and the foot target
//! would jump with it. A stepping stones' pit is no foothold either, where a stone is within
//! the stride: its floor is clear of edges, but a leg standing there tilts the body towards
//! it and its shin catches the stones' sides.

use glam::DVec3;

/// Ground that rises more steeply than this between two samples is an edge (tan 60°, the slope
/// beyond which the terrain itself reads a jump as a wall: physics.md).
const EDGE_SLOPE: f64 = 1.732;
/// Distance between the samples across a footprint (m).
const SAMPLE: f64 = 0.005;
/// Clear ground kept beyond the foot's radius on each side of a foothold (m).
pub const EDGE_MARGIN: f64 = 0.04;
/// The steps in which the search moves a foothold, as shares of its longest move.
const SEARCH_STEPS: usize = 12;

/// Whether `ground` (height of the terrain under a body-frame point) has an edge within the
/// square of half-width `half_width` about `p`: along the body's x and y, on the lines through
/// `p` and along the square's sides. The lines through `p` alone miss the crossing of two
/// trenches, where each runs inside one of them (hex18 on 2 cm stepping stones: its feet and
/// its body's ground were put where two pits cross, the body sank 4 cm and its femurs dragged).
pub fn near_edge(ground: &impl Fn(DVec3) -> f64, p: DVec3, half_width: f64) -> bool {
    let n = (half_width / SAMPLE).ceil() as i32;
    let step = half_width / n as f64;
    [(DVec3::X, DVec3::Y), (DVec3::Y, DVec3::X)]
        .iter()
        .any(|&(axis, across)| {
            [0.0, -half_width, half_width].iter().any(|&offset| {
                let line = p + across * offset;
                let mut last = ground(line - axis * half_width);
                (-n + 1..=n).any(|i| {
                    let h = ground(line + axis * (i as f64 * step));
                    let edge = (h - last).abs() > EDGE_SLOPE * step;
                    last = h;
                    edge
                })
            })
        })
}

/// The ground under a stance foot planned at `planned` whose centre is at `foot` (body frame,
/// `ground`'s points): the planned point's, unless an edge lies between the two and the foot
/// stands on its high side — then the ground under the foot. An edge is a rise steeper than
/// [`EDGE_SLOPE`] over their distance and the foot's radius (the foot's extent, where its
/// centre alone does not say which side of an edge it rests on).
///
/// A body that moves or pitches off its plan by a few centimetres carries a stance foot's
/// planned point across the ground while the foot stands still. Over a trench's edge the
/// planned ground drops by the trench's depth, and the leg, its target dropped with it, pushed
/// hex18's rear foot into the trench (perceptive, 6 cm gaps: the robot went over backwards).
/// Everywhere else the planned point's ground is kept: followed always, the ground under the
/// feet let a body that fell behind its plan on a 30° slope raise its own stance targets (the
/// feet ahead of their planned points, uphill) and slide back down. Under the foot's centre
/// only: the highest ground under its footprint lifted a foot standing in a trench by its wall
/// onto the wall's top, where it hung in the air (hex18's middle and rear feet touched down in
/// 26 % of the walk against 48 %).
pub fn stance_ground(
    ground: &impl Fn(DVec3) -> f64,
    planned: DVec3,
    foot: DVec3,
    radius: f64,
) -> f64 {
    let there = ground(planned);
    let under = ground(foot);
    let apart = (planned - foot).truncate().length() + radius;
    if under - there > EDGE_SLOPE * apart {
        under
    } else {
        there
    }
}

/// The ground a stance foot whose centre is at `foot` stands on, its plan's ground being
/// `planned_ground` (at `planned`, [`stance_ground`] and the swing's rim): that, unless an edge
/// lies between the two and the foot is over ground lower than planned — a pit beside the stone
/// its foothold was chosen on, the body lagging its plan — then the ground it rests on there
/// ([`resting_ground`]). Held at the planned height the foot hangs over the pit: bullet's
/// tripod set two feet down 9–10 cm above the pits' floors, and its body, carried by less
/// than half its weight, fell 4 cm onto a tarsus on a stone's edge (5.24 mm deep).
pub fn standing_ground(
    ground: &impl Fn(DVec3) -> f64,
    planned: DVec3,
    planned_ground: f64,
    foot: DVec3,
    radius: f64,
    sole: f64,
) -> f64 {
    let most_drop = EDGE_SLOPE * ((planned - foot).truncate().length() + radius);
    // the resting ground is never below the centre's: where that is not lower by the edge's
    // drop, neither is the resting ground, and its sampling of the footprint (read at every
    // step of every stance) is not needed
    if planned_ground - ground(foot) <= most_drop {
        return planned_ground;
    }
    let resting = resting_ground(ground, foot, sole);
    if planned_ground - resting > most_drop {
        resting
    } else {
        planned_ground
    }
}

/// The ground a foot reaching `radius` across stands on over `p` (body frame, `ground`'s points):
/// over a pit narrower than the foot, where it rests on the pit's rims; elsewhere, the ground
/// under its centre. The rims are read as a sphere of that radius centred above `p` rests on
/// them: on three rings of points across the footprint, each pair of opposite points holds it
/// at the lower of their grounds less the sphere's rise above its lowest point there,
/// r − √(r² − d²), and the highest pair, if above the centre's ground, is its ground. A flat
/// sole wider than its foot sphere is taken as a sphere its width, held on a pit's rims a
/// little lower than the flat pad is (WORMS's 0.115 m pads over 10 cm pits: 11 mm below the
/// rims, 24 mm where two pits cross).
///
/// Opposite points, not any one: high ground on one side alone (a stair's nose beside a foot
/// centred over the tread below) tips a sole off, down onto the lower ground; read as its
/// ground, WORMS's foot planned on a 12 cm stair's nose was pushed 7.2 mm into it. The ground
/// under the centre alone reads a pit narrower than the foot as the foot's ground: WORMS's feet
/// standing over 2 cm stepping stones' gaps had targets 10 cm down in the pits and back on the
/// stones as the settling body swayed a millimetre, and the legs threw the 79 kg body about
/// until the run stopped for runaway motion. Where the footprint holds no edge ([`near_edge`])
/// it is the centre's ground, as a walking stance foot reads it: on a slope a sphere rests a
/// little above its lowest point's ground (r·(1/cos θ − 1), 2.2 mm for a 1 cm foot on 35°).
pub fn resting_ground(ground: &impl Fn(DVec3) -> f64, p: DVec3, radius: f64) -> f64 {
    if !near_edge(ground, p, radius) {
        return ground(p);
    }
    let d = std::f64::consts::FRAC_1_SQRT_2;
    let axes = [(1.0, 0.0), (d, d), (0.0, 1.0), (-d, d)];
    let mut top = ground(p);
    for share in [0.35f64, 0.7, 0.95] {
        let rise = radius * (1.0 - (1.0 - share * share).sqrt());
        for (u, v) in axes {
            let off = DVec3::new(u, v, 0.0) * (share * radius);
            top = top.max(ground(p + off).min(ground(p - off)) - rise);
        }
    }
    top
}

/// The shift (body frame, horizontal) that moves the foothold `p` off any edge within
/// `radius + EDGE_MARGIN` of it: the shortest up to `longest`, tried along `direction` (the
/// leg's travel across the ground) first, then against it, to either side and diagonally (a
/// stone's rim may lie beside the foot); zero where `p` is clear. Where no shift within
/// `longest` clears that margin, the margin is halved, then dropped to the foot's radius
/// alone: on 2 cm stepping stones, where hex18's middle hips ride over a pit between two rows
/// of 15 cm stones, a full margin is out of reach, and the unmoved point stood in the pit.
pub fn away_from_edges(
    ground: &impl Fn(DVec3) -> f64,
    p: DVec3,
    direction: DVec3,
    radius: f64,
    longest: f64,
) -> DVec3 {
    away_from_edges_within(ground, p, direction, radius, longest, |_| true)
}

/// [`away_from_edges`] for a foot the leg must reach: the shortest shift (none, first) that
/// clears an edge and that `reaches` accepts (given the shift), else the shortest that clears
/// an edge, as [`away_from_edges`] chooses it — so a foothold clear of edges but out of reach
/// moves too, where a clear point within `longest` is reached. A foothold moved off a trench's
/// lip by most of a stride lies beyond the reach of a leg whose workspace is little more than
/// its stride (ant_bot, 2 cm gaps: front and rear feet moved 5 cm fore and aft, out of reach by
/// 3–4 cm through their stance, 10 750 steps in 25 s), and the foot that cannot stand on it
/// skates.
pub fn away_from_edges_within(
    ground: &impl Fn(DVec3) -> f64,
    p: DVec3,
    direction: DVec3,
    radius: f64,
    longest: f64,
    reaches: impl Fn(DVec3) -> bool,
) -> DVec3 {
    search(ground, p, direction, radius, longest, reaches, |_| true)
}

/// [`away_from_edges_within`], a pit avoided: the shortest shift that clears an edge, that
/// `reaches` accepts, and whose point is not in a pit ([`in_pit`]: lower than the ground
/// `longest` away on both sides by more than `pit_depth`); where there is none, as
/// [`away_from_edges_within`] chooses.
///
/// A pit's floor wider than the foot's footprint is clear of edges by half the margin, and
/// the edge search, which takes the nearest clear point, put feet there whenever the nearest
/// stone was farther: PhantomX perceptive on 6 and 8 cm stepping stones stood its stance feet
/// in 10 cm pits, rolled 29° onto its legs there, wedged a swinging leg across a pit between
/// its foot and shin (97 N, 6 weights) and sank a foot 5.5 mm under the falling body.
pub fn away_from_pits_within(
    ground: &impl Fn(DVec3) -> f64,
    p: DVec3,
    direction: DVec3,
    radius: f64,
    longest: f64,
    pit_depth: f64,
    reaches: impl Fn(DVec3) -> bool,
) -> DVec3 {
    let on_top = |shift: DVec3| !in_pit(ground, p + shift, longest, pit_depth);
    search(ground, p, direction, radius, longest, reaches, on_top)
}

/// Whether `p` lies more than `depth` below the ground `across` away on both sides of it, along
/// x, y or a diagonal (a stone's pit, a trench, a crossing of two).
pub fn in_pit(ground: &impl Fn(DVec3) -> f64, p: DVec3, across: f64, depth: f64) -> bool {
    let here = ground(p);
    let d = std::f64::consts::FRAC_1_SQRT_2;
    [
        DVec3::X,
        DVec3::Y,
        DVec3::new(d, d, 0.0),
        DVec3::new(d, -d, 0.0),
    ]
    .iter()
    .any(|&a| ground(p + a * across) - here > depth && ground(p - a * across) - here > depth)
}

/// The search of [`away_from_edges_within`]: the shortest clear shift that `reaches` and
/// `prefers` both accept, else the shortest clear shift that `reaches` accepts, else the
/// shortest clear shift. Each shift's reach is tested once.
fn search(
    ground: &impl Fn(DVec3) -> f64,
    p: DVec3,
    direction: DVec3,
    radius: f64,
    longest: f64,
    reaches: impl Fn(DVec3) -> bool,
    prefers: impl Fn(DVec3) -> bool,
) -> DVec3 {
    let ahead = DVec3::new(direction.x, direction.y, 0.0)
        .try_normalize()
        .unwrap_or(DVec3::X);
    let side = DVec3::Z.cross(ahead);
    let diagonal = std::f64::consts::FRAC_1_SQRT_2;
    let ways = [
        ahead,
        -ahead,
        side,
        -side,
        (ahead + side) * diagonal,
        (ahead - side) * diagonal,
        (-ahead + side) * diagonal,
        (-ahead - side) * diagonal,
    ];
    // the shifts in the order tried: none, then outwards a step at a time, every way each step
    let shifts = || {
        std::iter::once(DVec3::ZERO).chain((1..=SEARCH_STEPS).flat_map(move |i| {
            let along = longest * i as f64 / SEARCH_STEPS as f64;
            ways.map(|way| way * along)
        }))
    };
    // the first clear shift, whatever the reach: what the search without `reaches` returns;
    // and the first clear one reached, whether preferred or not
    let (mut nearest_clear, mut nearest_reached) = (None, None);
    // shifts found clear and tested: clear by a wider margin, they are clear by a narrower one
    // too, and neither their reach nor the preference is tested again
    let mut tested = [false; 1 + 8 * SEARCH_STEPS];
    for margin in [EDGE_MARGIN, 0.5 * EDGE_MARGIN, 0.0] {
        let half_width = radius + margin;
        for (n, shift) in shifts().enumerate() {
            if tested[n] || near_edge(ground, p + shift, half_width) {
                continue;
            }
            tested[n] = true;
            nearest_clear.get_or_insert(shift);
            if reaches(shift) {
                if prefers(shift) {
                    return shift;
                }
                nearest_reached.get_or_insert(shift);
            }
        }
    }
    nearest_reached.or(nearest_clear).unwrap_or(DVec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A riser 8 cm high at x = 0.3 m.
    fn riser(p: DVec3) -> f64 {
        if p.x < 0.3 { 0.0 } else { 0.08 }
    }

    #[test]
    fn a_foothold_on_level_ground_or_a_slope_stays() {
        let slope = |p: DVec3| 0.7 * p.x; // 35°
        for ground in [&(|_: DVec3| 0.0) as &dyn Fn(DVec3) -> f64, &slope] {
            let g = |p: DVec3| ground(p);
            let shift = away_from_edges(&g, DVec3::new(0.2, 0.1, -0.1), DVec3::X, 0.01, 0.05);
            assert_eq!(shift, DVec3::ZERO);
        }
    }

    /// A 5 cm foot over a 2 cm trench stands on its rims, 1.0 mm below them (r − √(r² − 1²) cm);
    /// over a 20 cm trench, on its floor; on a plane or a slope, on the ground under its centre;
    /// beside a riser, on the tread under its centre (high ground on one side tips it off).
    #[test]
    fn a_foot_rests_on_the_rims_of_a_pit_narrower_than_itself() {
        let trench = |width: f64| move |p: DVec3| if p.x.abs() < width / 2.0 { -0.1 } else { 0.0 };
        let r = 0.05;
        let narrow = resting_ground(&trench(0.02), DVec3::ZERO, r);
        let expected = -(r - (r * r - 0.01f64 * 0.01).sqrt());
        assert!(
            narrow <= 0.0 && narrow > -0.004,
            "{narrow} against {expected}"
        );
        assert_eq!(resting_ground(&trench(0.2), DVec3::ZERO, r), -0.1);
        assert_eq!(
            resting_ground(&|_| 0.03, DVec3::new(0.1, 0.2, 0.0), r),
            0.03
        );
        let slope = |p: DVec3| 0.7 * p.x; // 35°: no edge, the centre's ground
        let p = DVec3::new(0.1, 0.0, 0.0);
        assert_eq!(resting_ground(&slope, p, r), slope(p));
        // beside a riser, high ground on one side only: the lower tread
        assert_eq!(resting_ground(&riser, DVec3::new(0.29, 0.0, 0.0), r), 0.0);
        assert_eq!(resting_ground(&riser, DVec3::new(0.31, 0.0, 0.0), r), 0.08);
        assert_eq!(resting_ground(&riser, DVec3::new(0.2, 0.0, 0.0), r), 0.0);
    }

    /// A foothold 1 cm short of a riser moves back onto its tread, one 1 cm past it forward onto
    /// the next, each to a full footprint's clearance, no farther than needed.
    #[test]
    fn a_foothold_next_to_an_edge_moves_onto_the_tread() {
        let (radius, longest) = (0.01, 0.06);
        let clear = radius + EDGE_MARGIN;
        for (x, back) in [(0.29, true), (0.31, false), (0.3, false)] {
            let p = DVec3::new(x, 0.12, -0.1);
            assert!(near_edge(&riser, p, clear));
            let shift = away_from_edges(&riser, p, DVec3::X, radius, longest);
            let landed = p + shift;
            assert!(!near_edge(&riser, landed, clear), "{x}: {shift:?}");
            assert_eq!(landed.x < 0.3, back, "{x}: {shift:?}");
            assert!((landed.x - 0.3).abs() < clear + longest / SEARCH_STEPS as f64 + 1e-9);
            assert_eq!((shift.y, shift.z), (0.0, 0.0));
        }
        // beside a stone's rim (an edge along x), the foothold moves sideways
        let rim = |p: DVec3| if p.y < 0.0 { -0.1 } else { 0.0 };
        let shift = away_from_edges(&rim, DVec3::new(0.2, 0.01, -0.1), DVec3::X, radius, longest);
        assert!(shift.x.abs() < 1e-12 && shift.y > 0.02, "{shift:?}");
        // a full margin out of reach: the foot's own radius clear of the edge, then in place
        let p = DVec3::new(0.295, 0.0, 0.0);
        let landed = p + away_from_edges(&riser, p, DVec3::X, radius, 0.01);
        assert!(near_edge(&riser, landed, clear) && !near_edge(&riser, landed, radius));
        assert!(landed.x < 0.3 - radius && landed.x > 0.285, "{landed:?}");
        let p = DVec3::new(0.3, 0.0, 0.0);
        assert_eq!(
            away_from_edges(&riser, p, DVec3::X, radius, 0.001),
            DVec3::ZERO
        );
    }

    /// A foothold the leg must reach moves the nearest way its reach allows: 1 cm short of a
    /// riser, back onto the tread when the leg reaches back, else forward onto the next tread;
    /// where it reaches no clear point, the shift is the one without reach.
    #[test]
    fn a_foothold_within_reach_moves_the_way_the_leg_reaches() {
        let (radius, longest) = (0.01, 0.1);
        let p = DVec3::new(0.29, 0.12, -0.1);
        let back = away_from_edges(&riser, p, DVec3::X, radius, longest);
        assert!(back.x < 0.0);
        assert_eq!(
            away_from_edges_within(&riser, p, DVec3::X, radius, longest, |_| true),
            back
        );
        let forward = away_from_edges_within(&riser, p, DVec3::X, radius, longest, |s| {
            s.x > -0.001 && s.y.abs() < 1e-9
        });
        assert!(forward.x > 0.0 && forward.y == 0.0, "{forward:?}");
        assert!(!near_edge(&riser, p + forward, radius + EDGE_MARGIN));
        let nowhere = away_from_edges_within(&riser, p, DVec3::X, radius, longest, |_| false);
        assert_eq!(nowhere, back);
    }

    /// A foothold planned in a stepping stones' pit (8 cm between 15 cm stones, 10 cm deep) moves
    /// onto a stone, where the edge search alone keeps it on the pit's floor — clear of edges by
    /// half the margin; a foothold on a stair's lower tread beside its riser is not in a pit and
    /// moves as the edge search moves it.
    #[test]
    fn a_foothold_in_a_pit_moves_onto_a_stone() {
        let stones = |p: DVec3| {
            let in_pit = |u: f64| u.rem_euclid(0.23) >= 0.15;
            if in_pit(p.x) || in_pit(p.y) {
                -0.1
            } else {
                0.0
            }
        };
        let (radius, longest, depth) = (0.007, 0.067, 0.03);
        let middle = DVec3::new(0.19, 0.075, 0.0);
        assert!(in_pit(&stones, middle, longest, depth));
        let edges = away_from_edges_within(&stones, middle, DVec3::X, radius, longest, |_| true);
        assert_eq!(stones(middle + edges), -0.1, "{edges:?}");
        let shift =
            away_from_pits_within(&stones, middle, DVec3::X, radius, longest, depth, |_| true);
        let landed = middle + shift;
        assert_eq!(stones(landed), 0.0, "{landed:?}");
        assert!(!near_edge(&stones, landed, radius), "{landed:?}");
        // the middle of a stone is not a pit, nor is a lower tread
        assert!(!in_pit(
            &stones,
            DVec3::new(0.075, 0.075, 0.0),
            longest,
            depth
        ));
        let lower = |p: DVec3| if p.x < 0.3 { 0.0 } else { -0.08 };
        let p = DVec3::new(0.31, 0.0, 0.0);
        assert!(!in_pit(&lower, p, longest, depth));
        assert_eq!(
            away_from_pits_within(&lower, p, DVec3::X, radius, longest, depth, |_| true),
            away_from_edges_within(&lower, p, DVec3::X, radius, longest, |_| true)
        );
        // no stone within reach: the edge search's choice
        let nowhere =
            away_from_pits_within(&stones, middle, DVec3::X, radius, longest, depth, |s| {
                s == DVec3::ZERO
            });
        assert_eq!(nowhere, edges);
    }

    /// Where two trenches cross, the lines through the point run inside them and see no edge;
    /// the footprint's sides cross their walls.
    #[test]
    fn a_crossing_of_two_trenches_is_near_an_edge() {
        let pits = |p: DVec3| {
            let in_pit = |u: f64| (0.585..0.605).contains(&u);
            if in_pit(p.x) || in_pit(p.y) {
                -0.1
            } else {
                0.0
            }
        };
        assert!(near_edge(&pits, DVec3::new(0.595, 0.595, 0.0), 0.05));
        // a foothold on a stone's corner moves onto the stone, not into the crossing beside it
        let corner = DVec3::new(0.57, 0.57, 0.0);
        let landed = corner + away_from_edges(&pits, corner, DVec3::X, 0.01, 0.06);
        assert!(
            pits(landed) == 0.0 && !near_edge(&pits, landed, 0.05),
            "{landed:?}"
        );
        // the middle of a stone is clear
        assert!(!near_edge(&pits, DVec3::new(0.51, 0.51, 0.0), 0.05));
    }

    /// A stance foot standing 1 cm before a trench whose planned point the body has carried
    /// 2 cm past its edge stands on the tread; one planned on the tread, one standing in the
    /// trench by its wall, and one on a 30° slope 2 cm up or down from its planned point keep
    /// the planned point's ground.
    #[test]
    fn a_stance_foot_stands_on_the_ground_under_it() {
        let radius = 0.01;
        let trench = |p: DVec3| if p.x < 0.3 { 0.0 } else { -0.1 };
        let foot = DVec3::new(0.29, 0.1, -0.1);
        let over = DVec3::new(0.32, 0.1, -0.1);
        assert_eq!(stance_ground(&trench, over, foot, radius), 0.0);
        let on = DVec3::new(0.27, 0.1, -0.1);
        assert_eq!(stance_ground(&trench, on, foot, radius), 0.0);
        let by_the_wall = DVec3::new(0.305, 0.1, -0.2);
        assert_eq!(stance_ground(&trench, over, by_the_wall, radius), -0.1);
        let slope = |p: DVec3| 0.577 * p.x;
        for planned_x in [0.27, 0.31] {
            let planned = DVec3::new(planned_x, 0.1, -0.1);
            let g = stance_ground(&slope, planned, foot, radius);
            assert_eq!(g, slope(planned), "{planned_x}");
        }
    }

    /// A stance foot set down over a 10 cm pit 2 cm past the stone its foothold was planned on
    /// stands on the pit's floor, not in the air at the stone's height; one on the stone planned
    /// over the pit, one on a 30° slope off its planned point, one over a pit narrower than its
    /// sole (resting on the rims) and one whose planned point lies farther off than the pit is
    /// deep keep their planned ground.
    #[test]
    fn a_stance_foot_over_a_pit_beside_its_planned_stone_stands_in_the_pit() {
        let (radius, sole) = (0.01, 0.01);
        let pit = |p: DVec3| if p.x < 0.3 { 0.0 } else { -0.1 };
        let stone = DVec3::new(0.29, 0.1, -0.1);
        let over = DVec3::new(0.31, 0.1, -0.1);
        let planned = stance_ground(&pit, stone, over, radius);
        assert_eq!(planned, 0.0);
        assert_eq!(
            standing_ground(&pit, stone, planned, over, radius, sole),
            -0.1
        );
        let planned = stance_ground(&pit, over, stone, radius);
        assert_eq!(
            standing_ground(&pit, over, planned, stone, radius, sole),
            0.0
        );
        let slope = |p: DVec3| 0.577 * p.x;
        let g = slope(stone);
        assert_eq!(standing_ground(&slope, stone, g, over, radius, sole), g);
        let narrow = |p: DVec3| if (p.x - 0.31).abs() < 0.01 { -0.1 } else { 0.0 };
        let rims = resting_ground(&narrow, over, 0.05);
        assert!(rims > -0.005, "{rims}");
        assert_eq!(
            standing_ground(&narrow, stone, 0.0, over, radius, 0.05),
            0.0
        );
        let far = DVec3::new(0.36, 0.1, -0.1);
        assert_eq!(
            standing_ground(&pit, DVec3::new(0.29, 0.1, -0.1), 0.0, far, radius, sole),
            0.0
        );
    }
}
