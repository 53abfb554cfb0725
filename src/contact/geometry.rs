//! Where a sphere touches the terrain: the closest surface point, measured along the surface
//! normal (a sphere on a slope touches off-centre, not below its centre).

use crate::terrain::{GroundFrame, HeightGrid, Orientation};
use glam::DVec3;

/// A sphere's relation to the ground: signed gap and the ground frame at the contact point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereGeometry {
    /// Depth of the sphere below the surface along the normal, `r − d` (negative: a gap of −x).
    pub penetration: f64,
    /// The surface point closest to the sphere's centre (where the force acts).
    pub point: DVec3,
    /// Ground frame at `point`; its normal points out of the ground, towards the sphere.
    pub frame: GroundFrame,
}

/// The most fixed-point iterations for the closest surface point, and the step (m) below which it
/// has converged. On a plane the first is exact; where the ground curves the error shrinks by
/// about d·κ per iteration (d: the centre's distance, κ: the curvature), so a 50 mm ball in a
/// hollow of the ball-scale natural terrain (curvature radius ~60 mm) needs dozens where a
/// 10 mm foot needs three. Stopping early leaves the contact point off the normal through the
/// centre: the normal force then has a lever about the normal and spins the ball up (measured:
/// 1.9 mm off at 3 iterations, 1.5 rad/s² of spin, the held ball creeping downhill).
///
/// The tolerance, 1 nm, is far below every physical scale of a contact (a foot's 0.1–1 mm of
/// penetration, a terrain's features of centimetres; the gap is stationary at the closest
/// point, so the depth is off by far less), and keeps the ball in the hollow's bottom, where
/// d·κ ≈ 0.8, within 1 nm of the normal through its centre. It was 0.1 nm, one surface
/// evaluation more for some feet: 1.1k instructions of a walk's step; the walk's 20 s forward
/// distance moved by 10⁻⁷ of itself. (0.1 µm would save 3.4k, and leave the ball's contact
/// 40 nm off the normal: harmless against the 1.9 mm that spun it, but not the convergence
/// `converges_in_a_hollow_nearly_as_tight_as_the_ball` holds the search to.)
const CLOSEST_POINT_ITERATIONS: usize = 64;
const CLOSEST_POINT_TOLERANCE: f64 = 1e-9;

/// Finds the closest surface point to the sphere's centre: start below the centre, take the tangent
/// plane there, drop the perpendicular from the centre onto it, and repeat at the foot of that
/// perpendicular. The distance to the last tangent plane is the centre's height above the ground
/// measured along the normal.
///
/// A steep feature beside the centre — a stair's riser — can touch the sphere's side while the
/// ground beneath the centre is clear: when the search from below finds no contact but the
/// terrain within the sphere's footprint rises above its lowest point
/// ([`HeightGrid::ceiling_near`]), it is repeated from the footprint's four edges and the
/// deepest answer kept.
///
/// In a concave corner the sphere presses into several faces at once: this is their springs
/// summed into one contact ([`Faces::summed`]), for a reading that wants one (a sphere's depth
/// for a message, the ball under rolling resistance or spin friction, which act on one
/// contact); [`sphere_faces`] gives the faces one by one, each a contact of its own.
pub fn sphere_geometry(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
) -> SphereGeometry {
    sphere_faces(terrain, center, radius, orientation).summed(center, radius)
}

/// The surfaces a sphere presses into: one (or, clear of the ground, the nearest with its gap as
/// a negative depth) except in a concave corner of a grid with cliffs — a foot on a pit's floor
/// against its wall, a foot in a trench its own width — where each face it presses into is its
/// own contact (see [`Touching::faces`]).
pub fn sphere_faces(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
) -> Faces {
    sphere_faces_from(terrain, center, radius, orientation, &mut None)
}

/// [`sphere_faces`] for a sphere that touched the ground last step, its search from below
/// started where last step's ended: `last` holds the offset (x, y) from the centre to the
/// surface point that search converged on, and is left holding this step's (None where the
/// sphere is clear of the ground, or on a grid with cliffs, whose surface is searched from
/// below the centre always).
///
/// The closest point moves with the sphere by a few micrometres a step, so the search starts
/// within micrometres of it instead of millimetres (the sphere's centre over a slope): on a
/// smooth grid the closest point within a foot's reach is the one point where the normal
/// passes through the centre, and the search converges on it to the same nanometre from
/// either start, in about two surface evaluations fewer per foot (with the bicubic blend's
/// new order, 17.5k → 13.4k instructions of the terrain search in a walk's step on hex18).
pub fn sphere_faces_from(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    last: &mut Option<(f64, f64)>,
) -> Faces {
    let start = search_start(terrain, center, *last);
    let below = closest_from(terrain, center, radius, orientation, start);
    faces_from_below(terrain, center, radius, orientation, below, last)
}

/// Where [`sphere_faces_from`]'s search from below starts: where the last one ended, `last`
/// (an offset from the centre), on a smooth grid; else below the centre.
pub fn search_start(terrain: &HeightGrid, center: DVec3, last: Option<(f64, f64)>) -> (f64, f64) {
    match last {
        Some((dx, dy)) if !terrain.has_cliffs() => (center.x + dx, center.y + dy),
        _ => (center.x, center.y),
    }
}

/// [`sphere_faces_from`] from its search from below's answer `below` (the closest point found
/// from [`search_start`]: [`closest_from_each`] finds several spheres' at once).
pub fn faces_from_below(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    below: SphereGeometry,
    last: &mut Option<(f64, f64)>,
) -> Faces {
    let mut faces = Faces::single(below);
    faces_from_below_into(
        terrain,
        center,
        radius,
        orientation,
        below,
        last,
        &mut faces,
    );
    faces
}

/// [`faces_from_below`] written over `out` (any faces), for a loop over the feet: a single face
/// (nearly always) is written alone, not a whole [`Faces`] built and copied out (420 bytes, for
/// each foot on the ground every step).
pub fn faces_from_below_into(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    below: SphereGeometry,
    last: &mut Option<(f64, f64)>,
    out: &mut Faces,
) {
    let cliffs = terrain.has_cliffs();
    *last = (!cliffs && below.penetration > 0.0)
        .then_some((below.point.x - center.x, below.point.y - center.y));
    if cliffs {
        *out = among_walls(terrain, center, radius, orientation, below);
        return;
    }
    if below.penetration > 0.0 {
        // a second face of a crease the sphere sits in, found from the side it rises on (none
        // to look for, nearly always: the one face, as `Touching::faces` gives a single one)
        let starts = crease_starts(terrain, center, radius, &below);
        if starts.iter().all(Option::is_none) {
            out.set_single(below);
            return;
        }
        let mut touching = Touching::default();
        touching.add(below);
        for start in starts.into_iter().flatten() {
            touching.add(closest_from(terrain, center, radius, orientation, start));
        }
        *out = touching.faces(below);
        return;
    }
    if terrain.ceiling_at_most(center.x, center.y, radius, center.z - radius) {
        out.set_single(below);
        return;
    }
    out.set_single(
        [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]
            .map(|(u, v)| (center.x + u * radius, center.y + v * radius))
            .into_iter()
            .map(|start| closest_from(terrain, center, radius, orientation, start))
            .fold(below, |deepest, g| {
                if g.penetration > deepest.penetration {
                    g
                } else {
                    deepest
                }
            }),
    );
}

/// The most faces a sphere is taken to press into at once in a concave corner (a pit's floor and
/// two walls, a box's side and the ground: three at most on a grid's walls and treads; one spare).
pub const MAX_FACES: usize = 4;

/// The faces a sphere presses into ([`sphere_faces`]): at least one, the nearest first. The
/// slots past them hold anything (an earlier sphere's faces, [`Faces::set_single`]): never
/// read, nor compared or shown.
#[derive(Clone, Copy)]
pub struct Faces {
    faces: [SphereGeometry; MAX_FACES],
    len: usize,
}

impl PartialEq for Faces {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl std::fmt::Debug for Faces {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl Faces {
    /// One surface (or the gap to the nearest).
    pub fn single(g: SphereGeometry) -> Self {
        Faces {
            faces: [g; MAX_FACES],
            len: 1,
        }
    }

    /// No faces yet, to be written over ([`faces_from_below_into`]): a buffer, not a result.
    pub const EMPTY: Faces = {
        const ZERO: SphereGeometry = SphereGeometry {
            penetration: 0.0,
            point: DVec3::ZERO,
            frame: GroundFrame {
                tangent_x: DVec3::ZERO,
                tangent_y: DVec3::ZERO,
                normal: DVec3::ZERO,
            },
        };
        Faces {
            faces: [ZERO; MAX_FACES],
            len: 0,
        }
    };

    /// Made [`Faces::single`] of `g` in place: its first slot and its length written alone.
    fn set_single(&mut self, g: SphereGeometry) {
        self.faces[0] = g;
        self.len = 1;
    }

    /// The faces, the nearest first (clear of the ground: that one alone, with a depth ≤ 0).
    pub fn as_slice(&self) -> &[SphereGeometry] {
        &self.faces[..self.len]
    }

    /// The faces' springs summed as one contact: depth vector Σ xᵢ·nᵢ, its length the depth and
    /// its direction the normal — exactly the springs' force (k·Σ xᵢ·nᵢ) for the linear law, and
    /// continuous as a face starts or stops touching. A sphere squeezed evenly between two faces
    /// gets no depth: the springs cancel.
    pub fn summed(&self, center: DVec3, radius: f64) -> SphereGeometry {
        let best = self.faces[0];
        if self.len == 1 {
            return best;
        }
        let sum: DVec3 = self
            .as_slice()
            .iter()
            .map(|g| g.penetration * g.frame.normal)
            .sum();
        let penetration = sum.length();
        if penetration < 1e-12 {
            return SphereGeometry {
                penetration: 0.0,
                ..best
            };
        }
        let normal = sum / penetration;
        SphereGeometry {
            penetration,
            point: center - (radius - penetration) * normal,
            frame: GroundFrame::from_normal(normal),
        }
    }
}

/// [`sphere_geometry`] on a grid with cliffs (`terrain/cliff.rs`): the surface is the treads and
/// the walls between them, so the closest point is the nearest of the tread found from below the
/// centre (and, if that is clear while the footprint holds higher ground, from the footprint's
/// edges and from the sample nearest the centre: a box's side under the cliff threshold is a
/// ramp one cell wide, which searches from the rim step over) and the closest point of each wall within reach. The nearest is kept, whichever side
/// the centre is on; the side itself is read from the height below the centre (the centre is in
/// the ground where it is lower than the surface above its own (x, y), walls included) — not from
/// a tangent plane, which on an upper tread reaching over the lower one would call a centre
/// beside the riser buried. On a wall's face the normal is horizontal; at its top edge it points
/// from the edge to the centre, as for any sphere touching a convex edge.
fn among_walls(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    below: SphereGeometry,
) -> Faces {
    if terrain.ceiling_at_most(center.x, center.y, radius, center.z - radius) {
        return Faces::single(below);
    }
    let buried = center.z < terrain.height(center.x, center.y);
    let depth = |distance: f64| radius + if buried { distance } else { -distance };
    let mut touching = Touching::default();
    let mut nearest = center.distance(below.point);
    let mut best = SphereGeometry {
        penetration: depth(nearest),
        ..below
    };
    touching.add(best);
    let starts = if best.penetration <= 0.0 {
        let at = |u: f64, v: f64| Some((center.x + u * radius, center.y + v * radius));
        [
            at(1.0, 0.0),
            at(-1.0, 0.0),
            at(0.0, 1.0),
            at(0.0, -1.0),
            terrain.nearest_sample(center, radius),
            None,
            None,
            None,
        ]
    } else {
        crease_starts(terrain, center, radius, &best)
    };
    for start in starts.into_iter().flatten() {
        let g = closest_from(terrain, center, radius, orientation, start);
        let distance = center.distance(g.point);
        let g = SphereGeometry {
            penetration: depth(distance),
            ..g
        };
        touching.add(g);
        if distance < nearest {
            nearest = distance;
            best = g;
        }
    }
    terrain.walls_near(center.x, center.y, radius, |wall| {
        let (point, face) = wall.closest(center);
        let offset = center - point;
        let distance = offset.length();
        let normal = if distance < 1e-12 {
            face
        } else if buried {
            -offset / distance
        } else {
            offset / distance
        };
        let g = SphereGeometry {
            penetration: depth(distance),
            point,
            frame: GroundFrame::from_normal(normal),
        };
        touching.add(g);
        if distance < nearest {
            nearest = distance;
            best = g;
        }
    });
    if buried {
        Faces::single(best)
    } else {
        touching.faces(best)
    }
}

/// Where to look for a second face of a crease a sphere pressing into `found` may sit in: the
/// points of its footprint, 0.7·r from the centre in eight directions, where the ground rises
/// both above `found`'s tangent plane (concave) and into the sphere. The closest-point search
/// converges on one face of a V-shaped groove — whichever the centre is nearer — and the sphere
/// pressing into both got the nearest's spring alone: far more than the two together, which
/// nearly cancel, and on the other face the next step. A foot in a groove between two boxes
/// (faces at 62° and 49° a centimetre apart, `ladder/obstacles.toml` at 2 cm, perceptive) swung
/// from face to face 0.3, 2.2, 1.6, 2.9, 3.7, 4.8, 5.6, 7.4 … 10 m/s, each step faster, until it
/// was 8.2 mm deep. On a plane or a bump the ground never rises above the tangent plane, and in
/// a hollow wider than the sphere it rises into the sphere only near the contact (within
/// √(2·r·x) of it, 3 mm for a 1 cm foot 0.4 mm deep): nothing more is searched there.
fn crease_starts(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    found: &SphereGeometry,
) -> [Option<(f64, f64)>; 8] {
    const REACH: f64 = 0.7;
    let n = found.frame.normal;
    if n.z <= 1e-6 {
        return [None; 8]; // a wall's face: no tangent plane over the ground
    }
    // the sphere's lower surface at REACH·r from its centre's vertical
    let sphere = center.z - radius * (1.0 - REACH * REACH).sqrt();
    // nothing around rises that high (the cells' bounds): no probe can fire
    if terrain.ceiling_at_most(center.x, center.y, REACH * radius, sphere) {
        return [None; 8];
    }
    // nor, on a smooth grid, can the ground curve up into the sphere this close to the contact:
    // it rises above the tangent plane at most K·L²/2 a distance L off
    let curvature = terrain.curvature_near(center.x, center.y, radius);
    let s = std::f64::consts::FRAC_1_SQRT_2;
    let directions = [
        (1.0, 0.0),
        (s, s),
        (0.0, 1.0),
        (-s, s),
        (-1.0, 0.0),
        (-s, -s),
        (0.0, -1.0),
        (s, -s),
    ];
    // a loop, not the array's `map` (whose closure was called per probe, its invariants
    // computed again each time): the same arithmetic
    let mut starts = [None; 8];
    for (start, (u, v)) in starts.iter_mut().zip(directions) {
        let (x, y) = (center.x + REACH * radius * u, center.y + REACH * radius * v);
        let plane = found.point.z - (n.x * (x - found.point.x) + n.y * (y - found.point.y)) / n.z;
        if let Some(k) = curvature {
            // the distance along the tangent plane, its horizontal one over cos(tilt), squared
            // (no root: libm's `hypot` was most of the probes' cost)
            let (u, v) = (x - found.point.x, y - found.point.y);
            let along2 = (u * u + v * v) / (n.z * n.z);
            if 0.5 * k * along2 <= sphere - plane {
                continue;
            }
        }
        let h = terrain.height(x, y);
        *start = (h > plane + 1e-6 && h > sphere).then_some((x, y));
    }
    starts
}

/// The surfaces (treads, wall faces, edges) a sphere clear of the ground with its centre
/// reaches into, each with its depth and normal, for [`Touching::faces`].
#[derive(Default)]
struct Touching {
    found: [Option<SphereGeometry>; 8],
    count: usize,
}

impl Touching {
    fn add(&mut self, g: SphereGeometry) {
        if g.penetration > 0.0 && self.count < self.found.len() {
            self.found[self.count] = Some(g);
            self.count += 1;
        }
    }

    /// In a concave corner — a foot on a pit's floor against its wall, a sphere between a
    /// box's side and the ground, a foot in a trench its own width — the sphere presses into
    /// each surface at once; the nearest alone (the closest point) flips between them as the
    /// sphere moves, the force turning 90° with the depth unchanged from one step to the next,
    /// and the two springs, each missing every other step, let the foot chatter into the wall
    /// and the floor (measured on `ladder/stones.toml` at gap 0.06, perceptive: a foot in a
    /// pit's corner swinging 4, 6, 11, 21, 27 mm step to step until its centre was 5.6 mm inside
    /// the stone, a divergence). So every surface that faces the others — each one's contact
    /// point on the outer side of the other's tangent plane — is a face the sphere presses
    /// into. A convex edge and the tread beside it do not face each other (the edge lies in the
    /// tread's plane), nor do the pieces of one face: those keep the nearest alone, so a sphere
    /// touching one surface gets what it got before, bit for bit.
    fn faces(&self, best: SphereGeometry) -> Faces {
        let mut faces = Faces::single(best);
        if self.count < 2 {
            return faces;
        }
        // faces another surface: its point beyond the other's tangent plane, and the other's
        // beyond its own (1 µm: a contact point on a face's plane, as an edge on its tread's,
        // does not face it)
        let facing = |a: &SphereGeometry, b: &SphereGeometry| {
            (b.point - a.point).dot(a.frame.normal) > 1e-6
                && (a.point - b.point).dot(b.frame.normal) > 1e-6
        };
        // deepest first, so that of two pieces of one face the deeper is kept
        let mut order: [usize; 8] = std::array::from_fn(|k| k);
        let found = &self.found[..self.count];
        let depth_of = |k: usize| found[k].map_or(f64::NEG_INFINITY, |g| g.penetration);
        order[..self.count].sort_by(|&a, &b| depth_of(b).total_cmp(&depth_of(a)));
        for &k in &order[..self.count] {
            let Some(g) = found[k] else { continue };
            if faces.len < MAX_FACES && faces.as_slice().iter().all(|c| facing(c, &g)) {
                faces.faces[faces.len] = g;
                faces.len += 1;
            }
        }
        faces
    }
}

/// The fixed-point search for the closest surface point, from the ground at `start`. The gap is
/// measured to the surface point the search ends on (signed by the side of its tangent plane the
/// centre lies on), not to that point's tangent plane: once converged the two agree, but on a
/// sharp feature where three iterations do not converge the plane of an upper stair tread would
/// extend over the lower one and report a foot above the lower tread as sunk into it (seen on
/// `terrains/steps.toml`: 4.6 mm out of nothing). A surface point's distance never exceeds the
/// true gap's, so an unconverged search can miss depth but never invent it.
fn closest_from(
    terrain: &HeightGrid,
    center: DVec3,
    radius: f64,
    orientation: Orientation,
    start: (f64, f64),
) -> SphereGeometry {
    let mut search = Search::new(terrain, orientation, center, start);
    for _ in 1..CLOSEST_POINT_ITERATIONS {
        if !search.advance(terrain, orientation) {
            break;
        }
    }
    search.finish(terrain, orientation, radius)
}

/// [`closest_from`] for up to six spheres at once, in their order: `spheres` their centres,
/// radii and starts (a robot's feet, each from [`search_start`]). Each sphere's search is its own,
/// the same arithmetic, but they take turns, an iteration of each a round: alone, a search is
/// one chain of latencies (each iteration's surface, square root and division wait on the
/// last's), and the processor works on one sphere's iteration while another's waits.
pub fn closest_from_each(
    terrain: &HeightGrid,
    orientation: Orientation,
    spheres: &[(DVec3, f64, (f64, f64))],
) -> [Option<SphereGeometry>; 6] {
    let mut searches: [Option<Search>; 6] = [None; 6];
    assert!(spheres.len() <= searches.len(), "at most six at once");
    for (search, &(center, _, start)) in searches.iter_mut().zip(spheres) {
        *search = Some(Search::new(terrain, orientation, center, start));
    }
    let searches = &mut searches[..spheres.len()];
    let mut going = [true; 6];
    for _ in 1..CLOSEST_POINT_ITERATIONS {
        let mut any = false;
        for (search, going) in searches.iter_mut().zip(&mut going) {
            if *going {
                let search = search.as_mut().expect("set above");
                *going = search.advance(terrain, orientation);
                any |= *going;
            }
        }
        if !any {
            break;
        }
    }
    let mut found = [None; 6];
    for ((search, &(_, radius, _)), found) in searches.iter().zip(spheres).zip(&mut found) {
        *found = search.map(|s| s.finish(terrain, orientation, radius));
    }
    found
}

/// The closest-point search's state between iterations ([`closest_from`]).
#[derive(Clone, Copy)]
struct Search {
    center: DVec3,
    x: f64,
    y: f64,
    surface: DVec3,
    normal: DVec3,
    /// Where d·κ < −1 (the centre beyond the hollow's centre of curvature) the plain iteration
    /// overshoots and oscillates: each time a step grows, the steps are shortened by half.
    relax: f64,
    last_step: f64,
}

impl Search {
    /// The search at `start`, on the ground there.
    fn new(
        terrain: &HeightGrid,
        orientation: Orientation,
        center: DVec3,
        (x, y): (f64, f64),
    ) -> Self {
        let (height, normal) = height_and_normal(terrain, orientation, x, y);
        Search {
            center,
            x,
            y,
            surface: DVec3::new(x, y, height),
            normal,
            relax: 1.0,
            last_step: f64::INFINITY,
        }
    }

    /// One iteration: the foot of the perpendicular from the centre onto the tangent plane, and
    /// the ground there. False (nothing moved) once the step to it is below the tolerance.
    #[inline]
    fn advance(&mut self, terrain: &HeightGrid, orientation: Orientation) -> bool {
        let Search { x, y, .. } = *self;
        let distance = (self.center - self.surface).dot(self.normal);
        let foot = self.center - distance * self.normal;
        let step = ((foot.x - x).powi(2) + (foot.y - y).powi(2)).sqrt();
        if step < CLOSEST_POINT_TOLERANCE {
            return false;
        }
        if step > self.last_step {
            self.relax *= 0.5;
        }
        self.last_step = step;
        let relax = self.relax;
        (self.x, self.y) = (x + relax * (foot.x - x), y + relax * (foot.y - y));
        let height;
        (height, self.normal) = height_and_normal(terrain, orientation, self.x, self.y);
        self.surface = DVec3::new(self.x, self.y, height);
        true
    }

    /// The contact where the search stands: its ground frame (made once, here: the exact
    /// normal's frame is a function of the normal alone) and the gap to its surface point.
    fn finish(
        &self,
        terrain: &HeightGrid,
        orientation: Orientation,
        radius: f64,
    ) -> SphereGeometry {
        let frame = match orientation {
            Orientation::Exact => GroundFrame::from_normal(self.normal),
            Orientation::Paper { .. } => terrain.height_and_frame(self.x, self.y, orientation).1,
        };
        let offset = self.center - self.surface;
        let distance = offset.length().copysign(offset.dot(frame.normal));
        SphereGeometry {
            penetration: radius - distance,
            point: self.surface,
            frame,
        }
    }
}

/// The ground's height and normal at (x, y): all the search needs at each point.
#[inline]
fn height_and_normal(
    terrain: &HeightGrid,
    orientation: Orientation,
    x: f64,
    y: f64,
) -> (f64, DVec3) {
    match orientation {
        Orientation::Exact => {
            let s = terrain.surface(x, y);
            (s.height, s.normal())
        }
        Orientation::Paper { .. } => {
            let (height, frame) = terrain.height_and_frame(x, y, orientation);
            (height, frame.normal)
        }
    }
}

#[cfg(test)]
mod tests;
