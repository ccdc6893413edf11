//! The report's table rows: one per image (a scene that failed before
//! rendering gets one row of its own), with the thumbnails, the metrics, the
//! time and the threshold the image was judged by, in words and numbers.

use super::{escape, plural, seconds, url};
use crate::report::{ImageEntry, SceneEntry, Verdict};
use std::fmt::Write;

/// The scene and image cell: `hw1/xml/` small, the file name bold, the
/// encoding as a badge, then the image (name, size, notes) and, on a scene's
/// first row, its warnings folded.
fn scene_cell(h: &mut String, scene: &SceneEntry, img: Option<&ImageEntry>, first: bool) {
    let (dir, file) = match scene.label.rfind('/') {
        Some(i) => scene.label.split_at(i + 1),
        None => ("", scene.label.as_str()),
    };
    let _ = write!(
        h,
        "<td class=\"scene\"><span class=\"dir\">{}</span><span class=\"label\" title=\"{}\">{}</span>",
        escape(dir),
        escape(&scene.scene),
        escape(file)
    );
    let _ = write!(h, "<span class=\"enc {0}\">{0}</span>", escape(&scene.encoding));
    if let Some(img) = img {
        let _ = write!(h, "<span class=\"image\">→ {}", escape(&img.image_name));
        if let Some(m) = &img.metrics {
            let _ = write!(h, " · {}×{}", m.width, m.height);
        }
        h.push_str("</span>");
        if let (Some(e), Some(_)) = (&img.error, &img.metrics) {
            // Compared, but something else went wrong (a thumbnail, a copy): say so.
            let _ = write!(h, "<div class=\"note\">{}</div>", escape(e));
        }
        if let Some(q) = &img.quirk {
            let _ = write!(h, "<div class=\"note\">{}</div>", escape(q));
        }
    }
    if first && !scene.unsupported.is_empty() {
        let _ = write!(h, "<div class=\"note\">unsupported: {}</div>", escape(&scene.unsupported.join(", ")));
    }
    if first && !scene.warnings.is_empty() {
        let _ = write!(
            h,
            "<details><summary>{} warning{}</summary><ul>",
            scene.warnings.len(),
            plural(scene.warnings.len())
        );
        for w in &scene.warnings {
            let _ = write!(h, "<li>{}</li>", escape(w));
        }
        h.push_str("</ul></details>");
    }
    h.push_str("</td>");
}

fn row_start(h: &mut String, scene: &SceneEntry, verdict: Verdict, first: bool) {
    let _ = write!(
        h,
        "<tr class=\"row {}{}\" data-verdict=\"{}\" data-label=\"{}\">",
        verdict.name(),
        if first { " first" } else { "" },
        verdict.name(),
        escape(&scene.label.to_lowercase())
    );
}

fn verdict_cell(h: &mut String, v: Verdict) {
    let text = match v {
        Verdict::Pass => "PASS",
        Verdict::Fail => "FAIL",
        Verdict::Error => "ERROR",
        Verdict::NoReference => "NO REF",
        Verdict::Unsupported => "UNSUPPORTED",
        Verdict::KnownQuirk => "DATA QUIRK",
    };
    let _ = write!(h, "<td><span class=\"verdict {}\">{text}</span></td>", v.name());
}

pub fn scene_rows(h: &mut String, scene: &SceneEntry) {
    if let Some(v) = scene.verdict() {
        row_start(h, scene, v, true);
        scene_cell(h, scene, None, true);
        verdict_cell(h, v);
        let what = scene.error.as_deref().unwrap_or("the scene has no cameras");
        let _ = write!(
            h,
            "<td colspan=\"7\"><pre class=\"err\">{}</pre></td><td class=\"num\">{}</td><td></td>",
            escape(what),
            seconds(scene.seconds)
        );
        h.push_str("</tr>\n");
        return;
    }
    for (k, img) in scene.images.iter().enumerate() {
        row_start(h, scene, img.verdict, k == 0);
        scene_cell(h, scene, Some(img), k == 0);
        verdict_cell(h, img.verdict);
        image_cells(h, scene, img);
        h.push_str("</tr>\n");
    }
}

fn thumb(h: &mut String, full: Option<&str>, thumb: Option<&str>, alt: &str, missing: &str) {
    h.push_str("<td class=\"img\">");
    match (full, thumb) {
        (Some(f), Some(t)) => {
            let _ = write!(
                h,
                "<a href=\"{}\"><img src=\"{}\" loading=\"lazy\" alt=\"{}\"></a>",
                url(f),
                url(t),
                escape(alt)
            );
        }
        (Some(f), None) => {
            let _ = write!(h, "<a href=\"{}\">{}</a>", url(f), escape(alt));
        }
        _ => {
            let _ = write!(h, "<span class=\"none\">{}</span>", escape(missing));
        }
    }
    h.push_str("</td>");
}

fn image_cells(h: &mut String, scene: &SceneEntry, img: &ImageEntry) {
    thumb_cells(h, img);
    metric_cells(h, img);
    let _ = write!(
        h,
        "<td class=\"num\" title=\"load and build {}\">{}</td>",
        seconds(scene.setup_seconds),
        seconds(img.seconds)
    );
    threshold_cell(h, img);
}

/// Our render, the expected image (with their HDR previews) and the heatmap.
fn thumb_cells(h: &mut String, img: &ImageEntry) {
    let hdr = img.hdr.as_ref();
    let hdr_thumbs = hdr.and_then(|x| x.thumbs.as_ref());
    thumb(h, img.render.as_deref(), img.thumbs.render.as_deref(), "our render", "not rendered");
    if let (Some(x), Some([ours, _])) = (hdr, hdr_thumbs) {
        hdr_thumb(h, &x.render, ours);
    }
    thumb(h, img.expected.as_deref(), img.thumbs.expected.as_deref(), "expected image", "no expected image");
    if let (Some(orig), Some(_)) = (&img.expected_original, &img.expected) {
        // EXR/HDR: the thumbnail links to the preview; offer the original too.
        h.truncate(h.len() - "</td>".len());
        let _ = write!(h, "<span class=\"sub\">preview; <a href=\"{}\">original</a></span></td>", url(orig));
    }
    if let (Some(exp), Some([_, theirs])) = (hdr.and_then(|x| x.expected.as_ref()), hdr_thumbs) {
        hdr_thumb(h, exp, theirs);
    }
    thumb(h, img.heatmap.as_deref(), img.thumbs.heatmap.as_deref(), "LDR-FLIP heatmap", "no heatmap");
}

/// PSNR, SSIM, FLIP and the differing pixels, or why nothing was compared.
fn metric_cells(h: &mut String, img: &ImageEntry) {
    let hdr = img.hdr.as_ref();
    match &img.metrics {
        Some(m) => {
            let psnr = match m.psnr {
                Some(p) => format!("{p:.2} dB"),
                None => "∞ dB".to_string(),
            };
            let bad = |ok: bool| if ok { "num" } else { "num bad" };
            // An HDR row: the linear images' numbers under the 8-bit ones.
            let hdr_numbers = match hdr {
                Some(x) => format!(
                    "<span class=\"sub\" title=\"our .exr against the course's\">HDR-FLIP {:.4}<br>rel. MAE \
                     {:.2}%</span>",
                    x.hdr_flip,
                    x.relative_mae * 100.0
                ),
                None => String::new(),
            };
            let _ = write!(
                h,
                "<td class=\"{}\">{psnr}</td><td class=\"num\">{:.4}</td><td class=\"{}\">{:.4}{hdr_numbers}</td>",
                bad(m.psnr_ok),
                m.ssim,
                bad(m.flip_ok),
                m.flip
            );
            let bbox = match m.diff_bbox {
                Some([x0, y0, x1, y1]) => format!("; box x {x0}–{x1}, y {y0}–{y1}"),
                None => String::new(),
            };
            let _ = write!(
                h,
                "<td class=\"num\" title=\"{} pixels{}; max |Δ| {:.4} ({} values)\">{:.2} %\
                 <span class=\"sub\">{} px</span></td>",
                m.differing_pixels,
                escape(&bbox),
                m.max_abs_diff,
                m.space,
                m.differing_percent,
                m.differing_pixels
            );
        }
        None => {
            let text = match (&img.error, img.verdict) {
                (Some(e), _) => format!("<pre class=\"err\">{}</pre>", escape(e)),
                (None, Verdict::NoReference) => "not compared: the course has no expected image".to_string(),
                (None, _) => "not compared".to_string(),
            };
            let _ = write!(h, "<td colspan=\"4\">{text}</td>");
        }
    }
}

/// The bar the image was judged by, with the numbers it was judged on.
fn threshold_cell(h: &mut String, img: &ImageEntry) {
    let t = &img.threshold;
    // A noise-aware bar is judged against our own pair of renders: show the
    // pair's numbers under it, so the noise can be seen beside the bar.
    let pair = match (t.pair_psnr, t.pair_flip) {
        (p, Some(f)) => format!(
            "<span class=\"sub\">{} spp; seed pair {}, {f:.4}</span>",
            t.spp,
            p.map(|p| format!("{p:.2} dB")).unwrap_or_else(|| "∞ dB".to_string())
        ),
        _ => String::new(),
    };
    // The noise judgement: its space, blocks, z-scores and mean luminance,
    // red when missed.
    let coarse = match (t.max_mean_z2, t.max_outliers, t.max_luminance_z, img.metrics.as_ref()) {
        (Some(max_z2), Some(max_out), Some(max_lum), Some(m)) => {
            let num = |v: Option<f64>, f: &dyn Fn(f64) -> String| v.map(f).unwrap_or_else(|| "–".to_string());
            let lights = match m.left_out_blocks {
                Some(n) if n > 0 => format!(", {n} blocks left out (lights, clipped white)"),
                _ => String::new(),
            };
            format!(
                "<span class=\"sub{}\">{} {b}×{b} blocks{lights}: z² {} ≤ {max_z2}, |z|&gt;5 {} ≤ {:.1}%, \
                 luminance {} σ (≤ {max_lum})</span>",
                if m.z_ok { "" } else { " bad" },
                m.noise_space.unwrap_or("display"),
                num(m.block_mean_z2, &|z| format!("{z:.2}")),
                num(m.block_outliers, &|o| format!("{:.2}%", o * 100.0)),
                max_out * 100.0,
                num(m.luminance_z, &|z| format!("{z:+.2}")),
                b = m.block.unwrap_or(8),
            )
        }
        _ => String::new(),
    };
    if t.kind == "statistical" {
        // Perlin images: mean and contrast of luma, ours / expected.
        let stats = match img.metrics.as_ref().and_then(|m| Some((m, m.mean_luma?, m.contrast?))) {
            Some((m, mean, contrast)) => format!(
                "<span class=\"sub{}\">mean {:.3} / {:.3}<br>contrast {:.3} / {:.3}</span>",
                if m.stats_ok { "" } else { " bad" },
                mean[0],
                mean[1],
                contrast[0],
                contrast[1]
            ),
            None => String::new(),
        };
        let _ = write!(
            h,
            "<td><span class=\"thr\" title=\"{}\">statistical<br>FLIP ≤ {:.4}</span>{stats}</td>",
            escape(&t.reason),
            t.max_flip
        );
        return;
    }
    let floor = if t.min_psnr > f64::NEG_INFINITY {
        format!("PSNR ≥ {:.2}<br>FLIP ≤ {:.4}", t.min_psnr, t.max_flip)
    } else {
        "noise-aware, linear".to_string()
    };
    let _ = write!(
        h,
        "<td><span class=\"thr\" title=\"{}\">{floor}</span>{pair}{coarse}</td>",
        escape(&t.reason)
    );
}

/// The tone-mapped thumbnail of an HDR file, appended to the cell just written.
fn hdr_thumb(h: &mut String, full: &str, thumb: &str) {
    h.truncate(h.len() - "</td>".len());
    let _ = write!(
        h,
        "<a href=\"{}\" title=\"linear image, tone-mapped by the curve the course's image calls for\">\
         <img class=\"hdr\" src=\"{}\" loading=\"lazy\" alt=\"HDR image, tone-mapped\"></a>\
         <span class=\"sub\">HDR, same curve</span></td>",
        url(full),
        url(thumb)
    );
}
