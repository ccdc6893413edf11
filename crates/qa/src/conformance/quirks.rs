//! Known quirks of the course's data (see the shared folder's README): images
//! whose miss is the data's, not ours.

use super::Case;

/// Known quirks of the course's data (see the shared folder's README): an
/// image whose scene file is not the scene its expected image shows, or
/// that disagrees with the course's own images of the same scene.
/// (homework, encoding or "*", image name — `*suffix` matches every name
/// whose stem ends so —, the quirk). Such an image is judged by its usual
/// bar and shown with its numbers, but a miss is counted as the data's, not
/// ours.
const QUIRKS: &[(&str, &str, &str, &str)] = &[
    (
        "hw7",
        "*",
        "*_russian",
        "data quirk: the course's Russian-roulette images are 1.30–1.55× as bright (mean luminance) as \
         its own images of the same scene and year without roulette (diffuse 1.093 against 0.748 in \
         2022), which an unbiased estimator converges to; the course's roulette rule is not known",
    ),
    (
    "hw4",
    "json",
    "bump_mapping_transformed.png",
    "data quirk: the 2025 JSON scales the ellipsoid by (-1.5, 1, 1), the XML by (-2, 1, 1), and the only \
     expected image was rendered from the XML",
    ),
];

/// The known data quirk of one camera's image of a case, if any.
pub fn known_quirk(case: &Case, image_name: &str) -> Option<&'static str> {
    QUIRKS
        .iter()
        .find(|(hw, enc, name, _)| {
            *hw == case.hw && (*enc == "*" || *enc == case.encoding.name()) && name_matches(name, image_name)
        })
        .map(|q| q.3)
}

/// Whether an image name matches a table's name: exactly, or, for
/// `*suffix`, when the name's stem ends with `suffix` (`*_russian` matches
/// `glass_russian.exr`).
fn name_matches(pattern: &str, image_name: &str) -> bool {
    match pattern.strip_prefix('*') {
        Some(suffix) => std::path::Path::new(image_name)
            .file_stem()
            .is_some_and(|s| s.to_string_lossy().ends_with(suffix)),
        None => pattern == image_name,
    }
}
