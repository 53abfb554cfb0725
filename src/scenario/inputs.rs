//! The files a scenario is made from, each with a digest of its content: the robot's URDF, its
//! robot file and every mesh the URDF names (feet and contact spheres are read from meshes), the
//! gait file, the terrain file and its height data. Their digests, the scenario's fields and
//! hexsim's version make its fingerprint ([`super::Scenario::hash`]), which `batch --resume` and
//! `optimize --resume/--shard` compare: a result is reused only while none of them changed, and
//! what changed is named.
//!
//! The scenario file itself stands in by its parsed fields rather than its bytes: a comment edited
//! in a sweep, or an optimisation's generations extended, changes no run.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A file read, and the digest of what was in it.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// What it is, for messages ("robot", "mesh", "terrain's height file", …).
    pub what: &'static str,
    /// Where it was read, or a built-in's name (`robots/hex18.urdf (built in)`).
    pub path: PathBuf,
    /// The first 8 bytes of its content's SHA-256, in hex.
    pub digest: String,
    /// Built into hexsim, not read from a file.
    pub builtin: bool,
}

/// The files a scenario read, in the order it read them (each once).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Inputs(Vec<Input>);

impl Inputs {
    /// Digests the file at `path`, read within `limit` bytes ([`crate::limits`]). A file that is
    /// not there is left out: the loader that needs it names it.
    pub fn file(&mut self, what: &'static str, path: &Path, limit: u64) -> Result<(), String> {
        if self.0.iter().any(|i| i.path == path) {
            return Ok(());
        }
        let Ok(file) = std::fs::File::open(path) else {
            return Ok(());
        };
        let mut reader = crate::limits::Bounded::new(file, limit, limit);
        let mut hasher = Sha256::new();
        let mut buffer = vec![0u8; 1 << 16];
        loop {
            match std::io::Read::read(&mut reader, &mut buffer) {
                Ok(0) => break,
                Ok(n) => hasher.update(&buffer[..n]),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(format!("{}: cannot read: {e}", path.display())),
            }
        }
        self.0.push(Input {
            what,
            path: path.to_path_buf(),
            digest: short(&hasher.finalize()),
            builtin: false,
        });
        Ok(())
    }

    /// Digests a built-in file's text.
    pub fn builtin(&mut self, what: &'static str, name: &str, text: &str) {
        self.0.push(Input {
            what,
            path: PathBuf::from(format!("{name} (built in)")),
            digest: short(&Sha256::digest(text.as_bytes())),
            builtin: true,
        });
    }

    /// The URDF at `path`, its robot file beside it, and every mesh its links name (visual or
    /// collision) that resolves to a file.
    pub fn robot(&mut self, path: &Path) -> Result<(), String> {
        let limit = crate::limits::TEXT_FILE_BYTES;
        self.file("robot", path, limit)?;
        self.file("robot file", &path.with_extension("toml"), limit)?;
        // a URDF that does not parse is refused by the loader, which says why
        let Ok(text) = crate::limits::read_to_string(path, limit) else {
            return Ok(());
        };
        let Ok(urdf) = urdf_rs::read_from_string(&text) else {
            return Ok(());
        };
        let base = path.parent().unwrap_or(Path::new(""));
        let geometries = urdf.links.iter().flat_map(|link| {
            let visual = link.visual.iter().map(|v| &v.geometry);
            visual.chain(link.collision.iter().map(|c| &c.geometry))
        });
        for geometry in geometries {
            if let urdf_rs::Geometry::Mesh { filename, .. } = geometry
                && let Ok(mesh) = crate::robot::mesh::resolve(filename, base)
            {
                self.file("mesh", &mesh, crate::limits::DATA_FILE_BYTES)?;
            }
        }
        Ok(())
    }

    pub fn iter(&self) -> impl Iterator<Item = &Input> {
        self.0.iter()
    }

    /// Each file's digest by its path (as a results record keeps them).
    pub fn digests(&self) -> BTreeMap<String, String> {
        self.0
            .iter()
            .map(|i| (i.path.display().to_string(), i.digest.clone()))
            .collect()
    }

    /// Each file's digest under what it is and its file name (`mesh foot.stl`): names that do
    /// not change with the folder a command is run from, or where a project is moved. Added to
    /// `into`; a name taken by another file's digest gets its count (`mesh foot.stl #2`).
    pub fn named_into(&self, into: &mut BTreeMap<String, String>) {
        for input in &self.0 {
            let file = input
                .path
                .file_name()
                .map_or(input.path.as_os_str(), |n| n)
                .to_string_lossy();
            let name = format!("{} {file}", input.what);
            let mut key = name.clone();
            let mut n = 1;
            while into.get(&key).is_some_and(|d| *d != input.digest) {
                n += 1;
                key = format!("{name} #{n}");
            }
            into.insert(key, input.digest.clone());
        }
    }

    /// Adds every file's digest to `hasher`, with what it is (not where: a scenario moved with
    /// its files is the same scenario).
    pub fn hash_into(&self, hasher: &mut Sha256) {
        for input in &self.0 {
            hasher.update(input.what.as_bytes());
            hasher.update(input.digest.as_bytes());
        }
    }
}

/// The files of `now` whose digest differs from the one `before` recorded, or that `before` did
/// not have, and those `before` had that `now` lacks: what changed, for a message.
pub fn changed(before: &BTreeMap<String, String>, now: &BTreeMap<String, String>) -> Vec<String> {
    let mut changed: Vec<String> = now
        .iter()
        .filter(|(path, digest)| before.get(*path) != Some(*digest))
        .map(|(path, _)| path.clone())
        .collect();
    changed.extend(before.keys().filter(|p| !now.contains_key(*p)).cloned());
    changed
}

/// The first 8 bytes of a digest, in hex.
pub fn short(digest: &[u8]) -> String {
    digest[..8].iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_digested_by_its_content_and_a_missing_one_left_out() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.stl");
        std::fs::write(&file, "solid a\nendsolid a\n").unwrap();
        let mut inputs = Inputs::default();
        inputs.file("mesh", &file, 1 << 20).unwrap();
        inputs
            .file("mesh", &dir.path().join("absent.stl"), 1 << 20)
            .unwrap();
        // read once, however often it is named
        inputs.file("mesh", &file, 1 << 20).unwrap();
        assert_eq!(inputs.iter().count(), 1);
        let before = inputs.digests();
        std::fs::write(&file, "solid a\n\nendsolid a\n").unwrap();
        let mut again = Inputs::default();
        again.file("mesh", &file, 1 << 20).unwrap();
        assert_eq!(
            changed(&before, &again.digests()),
            vec![file.display().to_string()]
        );
        assert!(changed(&before, &before).is_empty());
    }

    #[test]
    fn a_file_past_its_limit_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("big.csv");
        std::fs::write(&file, vec![b'0'; 100]).unwrap();
        let error = Inputs::default().file("terrain", &file, 10).unwrap_err();
        assert!(error.contains("big.csv"), "{error}");
    }

    #[test]
    fn a_robot_brings_its_meshes() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("meshes")).unwrap();
        std::fs::write(dir.path().join("meshes/foot.stl"), "solid f\nendsolid f\n").unwrap();
        let urdf = dir.path().join("r.urdf");
        std::fs::write(
            &urdf,
            r#"<robot name="r"><link name="a"><collision><geometry>
               <mesh filename="meshes/foot.stl"/></geometry></collision></link></robot>"#,
        )
        .unwrap();
        let mut inputs = Inputs::default();
        inputs.robot(&urdf).unwrap();
        let whats: Vec<&str> = inputs.iter().map(|i| i.what).collect();
        assert_eq!(whats, ["robot", "mesh"]);
    }
}
