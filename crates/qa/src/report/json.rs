//! `results.json`: the [`Report`] serialised as it is, for scripts and CI.
//!
//! The shape follows the Rust types field by field: `summary` and
//! `homeworks[]` hold counts (`scenes`, `rows`, `passed`, `failed`,
//! `errored`, `no_reference`); `scenes[]` holds `label`, `hw`, `encoding`,
//! `error`, `warnings`, timings and `images[]`; each image has `verdict`
//! (`pass`, `fail`, `error`, `no-reference`), report-relative paths,
//! `metrics` and `threshold`. `metrics.psnr` is `null` when the PSNR is
//! infinite (the images are identical).
//!
//! ```json
//! { "summary": { "scenes": 2, "rows": 2, "passed": 1, "failed": 0, "errored": 1, "no_reference": 0 },
//!   "scenes": [ { "label": "hw1/xml/a.xml", "images": [ { "image_name": "a.png", "verdict": "pass",
//!                 "metrics": { "psnr": null, "ssim": 1.0, "flip": 0.0 } } ] } ] }
//! ```

use super::Report;

/// The report as pretty-printed JSON.
pub fn to_json(report: &Report) -> String {
    // Serialising plain structs of strings and numbers cannot fail; the
    // fallback only keeps this function total.
    serde_json::to_string_pretty(report).unwrap_or_else(|e| {
        serde_json::json!({ "error": format!("could not serialise the report: {e}") }).to_string()
    })
}
