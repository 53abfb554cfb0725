//! A link's visual mesh as the recording draws it. CAD exports carry far more triangles than a
//! viewer shows at a robot's scale (PhantomX's thigh has 40 000), and a recording holds a copy per
//! link (PhantomX's still picture was 17 MB, six copies of each leg's meshes): an STL over
//! [`MOST_TRIANGLES`] is drawn simplified by vertex clustering — its vertices merged per cell of
//! a grid, the finest grid that meets the budget — which keeps its outline to a cell.

use std::collections::{HashMap, HashSet};
use std::path::Path;

/// The most triangles a link's mesh is drawn with.
pub const MOST_TRIANGLES: usize = 4000;

/// A mesh to draw: vertices (in the file's units), their normals, triangles.
pub struct Simplified {
    pub vertices: Vec<[f32; 3]>,
    pub normals: Vec<[f32; 3]>,
    pub triangles: Vec<[u32; 3]>,
}

/// `path`'s STL simplified to at most [`MOST_TRIANGLES`]; None when it is not an STL, has no
/// more triangles than that, or cannot be read (the caller then draws the file as it is).
pub fn simplified_stl(path: &Path) -> Option<Simplified> {
    let stl = path.extension()?.to_str()?.eq_ignore_ascii_case("stl");
    if !stl {
        return None;
    }
    let mesh = stl_io::read_stl(&mut std::fs::File::open(path).ok()?).ok()?;
    if mesh.faces.len() <= MOST_TRIANGLES {
        return None;
    }
    let vertices: Vec<[f32; 3]> = mesh.vertices.iter().map(|v| v.0).collect();
    let triangles: Vec<[usize; 3]> = mesh.faces.iter().map(|f| f.vertices).collect();
    let (low, high) = vertices.iter().fold(
        ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
        |(lo, hi), v| {
            (
                [lo[0].min(v[0]), lo[1].min(v[1]), lo[2].min(v[2])],
                [hi[0].max(v[0]), hi[1].max(v[1]), hi[2].max(v[2])],
            )
        },
    );
    let extent = (0..3).map(|i| high[i] - low[i]).fold(0.0f32, f32::max);
    if !(extent.is_finite() && extent > 0.0) {
        return None;
    }
    // from 256 cells along the longest side, coarser by a quarter until within the budget
    let mut cells = 256.0f32;
    loop {
        let simplified = cluster(&vertices, &triangles, low, extent / cells);
        if simplified.triangles.len() <= MOST_TRIANGLES || cells < 8.0 {
            return Some(simplified);
        }
        cells *= 0.75;
    }
}

/// Merges the vertices in each `cell`-sized cube (from `low`) into their mean, and keeps the
/// triangles whose corners fall in three different cells, each once.
fn cluster(
    vertices: &[[f32; 3]],
    triangles: &[[usize; 3]],
    low: [f32; 3],
    cell: f32,
) -> Simplified {
    let mut cell_of: HashMap<[i32; 3], u32> = HashMap::new();
    let mut sums: Vec<([f64; 3], f64)> = Vec::new();
    let merged: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let key = [0, 1, 2].map(|i| ((v[i] - low[i]) / cell).floor() as i32);
            let k = *cell_of.entry(key).or_insert_with(|| {
                sums.push(([0.0; 3], 0.0));
                (sums.len() - 1) as u32
            });
            let (sum, n) = &mut sums[k as usize];
            for i in 0..3 {
                sum[i] += v[i] as f64;
            }
            *n += 1.0;
            k
        })
        .collect();
    let vertices: Vec<[f32; 3]> = sums
        .iter()
        .map(|(sum, n)| sum.map(|s| (s / n) as f32))
        .collect();
    let mut seen = HashSet::new();
    let triangles: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| t.map(|v| merged[v]))
        .filter(|[a, b, c]| a != b && b != c && a != c)
        .filter(|t| {
            let mut key = *t;
            key.sort_unstable();
            seen.insert(key)
        })
        .collect();
    // area-weighted vertex normals (a triangle's cross product is twice its area along its normal)
    let mut normals = vec![glam::Vec3::ZERO; vertices.len()];
    for t in &triangles {
        let [a, b, c] = t.map(|v| glam::Vec3::from_array(vertices[v as usize]));
        let n = (b - a).cross(c - a);
        for &v in t {
            normals[v as usize] += n;
        }
    }
    Simplified {
        normals: normals
            .iter()
            .map(|n| n.normalize_or(glam::Vec3::Z).to_array())
            .collect(),
        vertices,
        triangles,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PhantomX's thigh (40 000 triangles) is drawn with at most the budget, within its box.
    #[test]
    fn a_detailed_stl_is_drawn_within_the_budget() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/third_party/phantomx_description/meshes/thigh_l.STL"
        ));
        let mesh = simplified_stl(path).expect("over the budget");
        assert!(
            mesh.triangles.len() <= MOST_TRIANGLES && mesh.triangles.len() > MOST_TRIANGLES / 4,
            "{}",
            mesh.triangles.len()
        );
        assert_eq!(mesh.normals.len(), mesh.vertices.len());
        assert!(
            mesh.triangles
                .iter()
                .flatten()
                .all(|&v| (v as usize) < mesh.vertices.len())
        );
        // a small mesh is drawn as it is
        let small = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/data/third_party/phantomx_description/meshes/body_coll.STL"
        ));
        assert!(simplified_stl(small).is_none());
    }
}
