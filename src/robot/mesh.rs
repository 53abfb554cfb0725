//! Mesh files named by a URDF: where `package://NAME/...` and `file://` URIs point, and whether
//! the recording can draw the file.
//!
//! `package://NAME/rest` is resolved the ROS way, without ROS: each folder of `ROS_PACKAGE_PATH`
//! (a folder named NAME in it, or the folder itself if it is named NAME), then the URDF's own
//! folder and its parents (a folder named NAME beside or above the URDF). `file://PATH` is PATH;
//! anything else is relative to the URDF's folder.

use std::path::{Path, PathBuf};

/// Mesh formats rerun draws (STL, OBJ, glTF).
const DRAWABLE: [&str; 4] = ["stl", "obj", "gltf", "glb"];

/// Where a mesh URI points: the file, or every place looked in.
pub fn resolve(uri: &str, base: &Path) -> Result<PathBuf, Vec<PathBuf>> {
    let Some(rest) = uri.strip_prefix("package://") else {
        // `file://PATH` is PATH; relative paths resolve against the URDF's folder
        let path = base.join(uri.strip_prefix("file://").unwrap_or(uri));
        return if path.is_file() {
            Ok(path)
        } else {
            Err(vec![path])
        };
    };
    let (package, inside) = rest.split_once('/').unwrap_or((rest, ""));
    let mut roots: Vec<PathBuf> = std::env::var_os("ROS_PACKAGE_PATH")
        .map(|p| std::env::split_paths(&p).collect())
        .unwrap_or_default();
    roots.extend(base.ancestors().map(Path::to_path_buf));
    // a relative folder's ancestors stop at the working directory (a URDF named as
    // `hexapod.urdf` has the folder ""): the package folder above it is found from the full path
    let folder = if base.as_os_str().is_empty() {
        Path::new(".")
    } else {
        base
    };
    if let Ok(full) = folder.canonicalize() {
        roots.extend(full.ancestors().map(Path::to_path_buf));
    }
    let mut tried = Vec::new();
    for root in roots {
        let candidates = [
            Some(root.join(package).join(inside)),
            (root.file_name() == Some(package.as_ref())).then(|| root.join(inside)),
        ];
        for candidate in candidates.into_iter().flatten() {
            if candidate.is_file() {
                return Ok(candidate);
            }
            if !tried.contains(&candidate) {
                tried.push(candidate);
            }
        }
    }
    Err(tried)
}

/// The vertices of a URDF `<mesh>` (its `filename` resolved against `base`, its `scale` applied),
/// or why they could not be read (a sentence for a warning).
pub fn scaled_vertices(
    filename: &str,
    scale: Option<&urdf_rs::Vec3>,
    base: &Path,
) -> Result<Vec<glam::DVec3>, String> {
    let scale = scale.map_or(glam::DVec3::ONE, |s| glam::DVec3::from_array(s.0));
    match resolve(filename, base) {
        Ok(path) => match mesh_vertices(&path) {
            Some(vertices) => Ok(vertices.into_iter().map(|v| v * scale).collect()),
            None => Err(format!(
                "mesh {filename} is not a mesh file hexsim can read (STL, COLLADA, OBJ)"
            )),
        },
        Err(tried) => {
            let tried: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
            Err(match tried.as_slice() {
                [] => format!("mesh {filename} not found"),
                [only] => format!("mesh {filename} not found ({only} does not exist)"),
                all => format!("mesh {filename} not found (tried {})", all.join(", ")),
            })
        }
    }
}

/// Whether the recording can draw this mesh file (by its extension).
pub fn drawable(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| DRAWABLE.contains(&e.to_ascii_lowercase().as_str()))
}

/// Why a mesh file found cannot be drawn, by a check that reads no more than its first bytes: it
/// is empty, or an STL whose length is neither text nor its binary triangle count's.
pub fn unreadable(path: &Path) -> Option<String> {
    use std::io::Read;
    let length = std::fs::metadata(path).ok()?.len();
    if length == 0 {
        return Some("it is empty (0 bytes)".into());
    }
    let is_stl = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("stl"));
    if !is_stl {
        return None;
    }
    let mut head = [0u8; 84];
    let read = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .ok()?;
    if head[..read].trim_ascii_start().starts_with(b"solid") {
        return None;
    }
    let triangles = u32::from_le_bytes([head[80], head[81], head[82], head[83]]) as u64;
    (read < 84 || length != 84 + 50 * triangles).then(|| {
        format!(
            "not an STL mesh: {length} bytes, neither text nor a binary STL (whose header says {triangles} triangles, {} bytes)",
            84 + 50 * triangles
        )
    })
}

/// The vertices of a mesh file (in its own units; COLLADA's node transforms and `<unit>` applied
/// by mesh-loader — to the vertices, not to node translations: a node's −10 cm was read as
/// −10 m, so only a mesh placed by nodes in a unit other than metres comes out misplaced)
/// — STL, COLLADA (`.dae`, as Phobos and many ROS packages write them) or Wavefront OBJ — or
/// None if it cannot be read (the caller falls back to what it knows without the mesh).
pub fn mesh_vertices(path: &Path) -> Option<Vec<glam::DVec3>> {
    let extension = path.extension()?.to_str()?.to_ascii_lowercase();
    // a mesh is read whole: a device or a file past the data limit is not one
    let meta = std::fs::metadata(path).ok()?;
    if !meta.is_file() || meta.len() > crate::limits::DATA_FILE_BYTES {
        return None;
    }
    match extension.as_str() {
        "stl" => {
            let mut file = std::fs::File::open(path).ok()?;
            let mesh = stl_io::read_stl(&mut file).ok()?;
            Some(
                mesh.vertices
                    .iter()
                    .map(|v| glam::DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
                    .collect(),
            )
        }
        "dae" => scene_vertices(mesh_loader::Loader::default().load_collada(path)),
        "obj" => scene_vertices(mesh_loader::Loader::default().load_obj(path)),
        _ => None,
    }
}

/// Every vertex of a scene mesh-loader read, or None if it failed or holds none.
fn scene_vertices(scene: std::io::Result<mesh_loader::Scene>) -> Option<Vec<glam::DVec3>> {
    let vertices: Vec<glam::DVec3> = scene
        .ok()?
        .meshes
        .iter()
        .flat_map(|m| m.vertices.iter())
        .map(|v| glam::DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
        .collect();
    (!vertices.is_empty()).then_some(vertices)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A temporary folder, removed when the test ends.
    fn scratch(name: &str) -> tempfile::TempDir {
        let prefix = format!("hexsim-mesh-{name}-");
        tempfile::Builder::new().prefix(&prefix).tempdir().unwrap()
    }

    /// A ROS-style tree: robot_description/urdf/robot.urdf, meshes in robot_description/meshes.
    #[test]
    fn a_package_uri_resolves_to_the_package_folder_above_the_urdf() {
        let scratch = scratch("package");
        let root = scratch.path();
        let urdf_dir = root.join("my_robot_description/urdf");
        let meshes = root.join("my_robot_description/meshes");
        std::fs::create_dir_all(&urdf_dir).unwrap();
        std::fs::create_dir_all(&meshes).unwrap();
        std::fs::write(meshes.join("body.stl"), "solid x\nendsolid x\n").unwrap();
        let found = resolve("package://my_robot_description/meshes/body.stl", &urdf_dir).unwrap();
        assert_eq!(found, meshes.join("body.stl"));
        let missing = resolve("package://other_pkg/meshes/body.stl", &urdf_dir).unwrap_err();
        assert!(missing.contains(&urdf_dir.join("other_pkg/meshes/body.stl")));
        assert!(
            drawable(&found) && !drawable(Path::new("leg.DAE")) && drawable(Path::new("a.OBJ"))
        );
    }

    #[test]
    fn file_uris_and_relative_paths() {
        let scratch = scratch("file");
        let root = scratch.path();
        std::fs::write(root.join("a.obj"), "").unwrap();
        let absolute = format!("file://{}", root.join("a.obj").display());
        assert_eq!(
            resolve(&absolute, Path::new("/nowhere")).unwrap(),
            root.join("a.obj")
        );
        assert_eq!(resolve("a.obj", root).unwrap(), root.join("a.obj"));
    }

    /// A COLLADA mesh drawn in centimetres is read in metres (its `<unit>` applied by
    /// mesh-loader); a format hexsim does not read gives None.
    #[test]
    fn collada_vertices_are_read_in_metres() {
        let dae = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/meshes/tip_cm.dae");
        let mut found = mesh_vertices(&dae).unwrap();
        found.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        let expected = [
            glam::DVec3::new(0.0, 0.0, -0.1),
            glam::DVec3::new(0.0, 0.03, -0.1),
            glam::DVec3::new(0.02, 0.0, -0.1),
        ];
        assert_eq!(found.len(), 3, "{found:?}");
        for (f, e) in found.iter().zip(expected) {
            assert!(f.distance(e) < 1e-6, "{found:?}");
        }
        assert_eq!(mesh_vertices(Path::new("robot.ply")), None);
    }
}
