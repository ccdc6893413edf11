//! Finding a course folder's scenes: every `hwN/{json,xml}/**` scene file,
//! with the expected image of each camera (`hwN/expected/<ImageName>`, an
//! XML scene preferring `expected/2022/` and then `expected/2020/`).

use std::path::{Path, PathBuf};

/// Which encoding a scene uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Encoding {
    /// The 2025 JSON.
    Json,
    /// The older XML.
    Xml,
}

impl Encoding {
    /// `json` or `xml`.
    pub fn name(self) -> &'static str {
        match self {
            Encoding::Json => "json",
            Encoding::Xml => "xml",
        }
    }
}

/// A scene of a course folder.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Case {
    /// The homework folder name (`hw1`).
    pub hw: String,
    /// Its encoding.
    pub encoding: Encoding,
    /// The scene file.
    pub scene: PathBuf,
    /// The homework folder.
    pub hw_dir: PathBuf,
}

impl Case {
    /// A short, unique, human name: `hw2/xml/ellipsoids.xml`.
    pub fn label(&self) -> String {
        let rel = self.scene.strip_prefix(&self.hw_dir).unwrap_or(&self.scene);
        format!("{}/{}", self.hw, rel.display()).replace('\\', "/")
    }

    /// The expected image for a camera's `ImageName`, if the folder has one.
    ///
    /// A scene in a folder named `2020` takes `expected/2020/` first (the
    /// course re-rendered hw7 each year); any other XML scene `expected/2022/`
    /// and then `expected/2020/`; then `expected/` itself. An `.exr` image is
    /// compared through its `.png` sibling, the course's tone-mapped version,
    /// when there is one.
    pub fn expected_image(&self, image_name: &str) -> Option<PathBuf> {
        let exp = self.hw_dir.join("expected");
        let name = Path::new(image_name);
        let png = name.with_extension("png");
        let is_exr = name.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        let names: Vec<&Path> = if is_exr { vec![&png, name] } else { vec![name] };
        let in_2020 = self.scene.parent().is_some_and(|d| d.file_name().is_some_and(|n| n == "2020"));
        let years: &[&str] = match (self.encoding, in_2020) {
            (Encoding::Xml, true) => &["2020", "2022"],
            (Encoding::Xml, false) => &["2022", "2020"],
            (Encoding::Json, _) => &[],
        };
        let dirs = years.iter().map(|y| exp.join(y)).chain(std::iter::once(exp.clone()));
        dirs.flat_map(|d| names.iter().map(move |n| d.join(n)).collect::<Vec<_>>()).find(|p| p.is_file())
    }

    /// The course's HDR image for a camera whose `ImageName` is an `.exr` or
    /// `.hdr`, found as [`Case::expected_image`] finds images but without
    /// falling back to the `.png`: the linear radiance the noise judgement
    /// and the HDR metrics use.
    pub fn expected_hdr(&self, image_name: &str) -> Option<PathBuf> {
        let is_hdr = Path::new(image_name).extension().and_then(|e| e.to_str()).is_some_and(|e| {
            luster_core::image::output::HDR_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
        });
        self.expected_image(image_name).filter(|_| is_hdr).and_then(|ldr| {
            let hdr = ldr.with_file_name(Path::new(image_name).file_name()?);
            hdr.is_file().then_some(hdr)
        })
    }

    /// The other year's render of the image at `hdr` (an
    /// `expected/2022/` or `expected/2020/` file), when the folder has one:
    /// the course rendered hw7 in both years, so the pair measures its noise
    /// (see [`ref_noise`](super::ref_noise)).
    pub fn other_year(hdr: &Path) -> Option<PathBuf> {
        let dir = hdr.parent()?;
        let other = match dir.file_name()?.to_str()? {
            "2022" => "2020",
            "2020" => "2022",
            _ => return None,
        };
        let path = dir.parent()?.join(other).join(hdr.file_name()?);
        path.is_file().then_some(path)
    }

    /// Whether the scene file names one of its homework's expected images.
    ///
    /// A cheap textual test, made without loading the scene (and its meshes):
    /// true when the file's text contains the file name of an image in
    /// `hwN/expected/` (or, for XML, `expected/2022/` and `expected/2020/`).
    /// It errs on the side of true: a scene that fails to load is still kept
    /// if it mentions an expected image, so its failure gets reported.
    pub fn mentions_expected_image(&self) -> bool {
        // Through the checked reader: a FIFO or device here must not block.
        let Ok(bytes) = luster_core::file::read_bytes(&self.scene, 1 << 30) else { return true };
        let text = String::from_utf8_lossy(&bytes);
        let exp = self.hw_dir.join("expected");
        let mut dirs = vec![exp.clone()];
        if self.encoding == Encoding::Xml {
            dirs.extend(["2022", "2020"].map(|y| exp.join(y)));
        }
        dirs.iter().filter_map(|d| std::fs::read_dir(d).ok()).flat_map(|rd| rd.flatten()).any(|e| {
            let name = e.file_name();
            let name = name.to_string_lossy();
            e.path().is_file() && text.contains(name.as_ref())
        })
    }
}

/// Every scene file under `root/hw*/{json,xml}`, sorted.
pub fn discover(root: &Path) -> Vec<Case> {
    let mut cases = Vec::new();
    let Ok(hws) = std::fs::read_dir(root) else { return cases };
    for hw in hws.flatten() {
        let hw_dir = hw.path();
        let hw_name = hw.file_name().to_string_lossy().to_string();
        if !hw_dir.is_dir() || !hw_name.starts_with("hw") {
            continue;
        }
        for (sub, encoding) in [("json", Encoding::Json), ("xml", Encoding::Xml)] {
            let mut files = Vec::new();
            walk(&hw_dir.join(sub), sub, &mut files);
            for scene in files {
                cases.push(Case { hw: hw_name.clone(), encoding, scene, hw_dir: hw_dir.clone() });
            }
        }
    }
    cases.sort();
    cases
}

fn walk(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    walk_once(dir, ext, out, &mut std::collections::HashSet::new());
}

/// Walks each folder once, however symbolic links lead back to it, so a link
/// loop ends instead of recursing until the stack or the path length runs out.
fn walk_once(dir: &Path, ext: &str, out: &mut Vec<PathBuf>, seen: &mut std::collections::HashSet<PathBuf>) {
    let Ok(real) = std::fs::canonicalize(dir) else { return };
    if !seen.insert(real) {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            walk_once(&p, ext, out, seen);
        } else if p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case(ext)) {
            out.push(p);
        }
    }
}
