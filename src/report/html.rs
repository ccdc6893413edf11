//! `index.html`: the report as one self-contained page (inline CSS and a few
//! lines of script, images by relative path).
//!
//! At the top: counts by verdict, then one line per homework. Below, one row
//! per image with our render, the expected image and the LDR-FLIP heatmap
//! (thumbnails linking to the full-size files), the metrics, the render time,
//! the threshold (its reason on hover) and the verdict. Failed and errored
//! rows are tinted and marked in the margin; metrics that miss their bar are
//! red; buttons show only the problems or only the passes, and a search box
//! filters by scene label. Without script the page shows every row.
//!
//! Everything that comes from a scene, a file name or an error message goes
//! through [`escape`]; paths go through [`url`] as well.

use super::{Counts, ImageEntry, Report, SceneEntry, Verdict};
use std::fmt::Write;

/// Escapes text for HTML element content and quoted attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// A relative `/`-separated path as a URL, percent-encoded and HTML-escaped,
/// ready for an `href` or `src` attribute.
pub fn url(path: &str) -> String {
    let mut out = String::with_capacity(path.len());
    for b in path.bytes() {
        if b.is_ascii_alphanumeric() || matches!(b, b'-' | b'.' | b'_' | b'~' | b'/') {
            out.push(char::from(b));
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    escape(&out)
}

const STYLE: &str = r#"
:root { --pass:#1a7f37; --pass-bg:#eaf6ec; --fail:#cf222e; --fail-bg:#fdecea; --err:#a3440b;
        --err-bg:#fff0e0; --noref:#656d76; --line:#d8dee4; --muted:#57606a; }
* { box-sizing: border-box; }
body { font: 14px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; color:#1f2328;
       margin: 0; padding: 20px 28px 40px; background:#fff; }
h1 { font-size: 22px; margin: 0 0 4px; }
h2 { font-size: 15px; margin: 22px 0 8px; }
.meta { color: var(--muted); margin: 0 0 16px; }
code, pre { font-family: ui-monospace, SFMono-Regular, Menlo, Consolas, monospace; font-size: 12px; }
.cards { display: flex; gap: 12px; flex-wrap: wrap; }
.card { border: 1px solid var(--line); border-left-width: 6px; border-radius: 6px; padding: 8px 16px;
        min-width: 130px; }
.card b { display: block; font-size: 26px; line-height: 1.1; }
.card.pass { border-left-color: var(--pass); } .card.pass b { color: var(--pass); }
.card.fail { border-left-color: var(--fail); } .card.fail b { color: var(--fail); }
.card.error { border-left-color: var(--err); } .card.error b { color: var(--err); }
.card.noref { border-left-color: var(--noref); } .card.time { border-left-color: #0969da; }
table { border-collapse: collapse; }
table.hw td, table.hw th { padding: 3px 12px; border-bottom: 1px solid var(--line); text-align: right; }
table.hw td:first-child, table.hw th:first-child { text-align: left; }
table.hw tfoot td { font-weight: 600; border-bottom: none; }
.n-pass { color: var(--pass); } .n-fail { color: var(--fail); font-weight: 600; }
.n-error { color: var(--err); font-weight: 600; } .zero { color: #adb5bd; font-weight: normal; }
.bar { display: inline-flex; width: 160px; height: 10px; border-radius: 3px; overflow: hidden;
       background: #eef1f4; vertical-align: middle; }
.bar span { display: block; height: 100%; }
.bar .p { background: var(--pass); } .bar .f { background: var(--fail); } .bar .e { background: var(--err); }
.filters { margin: 20px 0 10px; display: flex; gap: 8px; align-items: center; flex-wrap: wrap; }
.filters button { font: inherit; padding: 4px 12px; border: 1px solid var(--line); border-radius: 16px;
                  background: #f6f8fa; cursor: pointer; }
.filters button.on { background: #1f2328; color: #fff; border-color: #1f2328; }
.filters input { font: inherit; padding: 4px 10px; border: 1px solid var(--line); border-radius: 6px;
                 width: 300px; margin-left: 8px; }
table.results { width: 100%; }
table.results th { position: sticky; top: 0; background: #f6f8fa; z-index: 1; text-align: left;
                   font-weight: 600; padding: 6px 6px; border-bottom: 2px solid var(--line); white-space: nowrap; }
table.results td { padding: 6px 6px; border-bottom: 1px solid var(--line); vertical-align: top; }
table.results td.num { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
tr.row { border-left: 6px solid transparent; }
tr.row.fail { background: var(--fail-bg); border-left-color: var(--fail); }
tr.row.error { background: var(--err-bg); border-left-color: var(--err); }
tr.row.pass { border-left-color: var(--pass); }
tr.row.no-reference, tr.row.unsupported, tr.row.known-quirk { border-left-color: var(--noref); }
tr.first td { border-top: 1px solid #afb8c1; }
td.scene { min-width: 210px; max-width: 260px; overflow-wrap: break-word; }
td.scene .dir { display: block; color: var(--muted); font-size: 12px; }
td.scene .label { font-weight: 600; }
td.scene .image { display: block; margin-top: 2px; font-size: 12px; }
.enc { display: inline-block; font-size: 11px; padding: 0 6px; border-radius: 8px; background: #ddf4ff;
       color: #0550ae; margin-left: 4px; }
.enc.xml { background: #fbefff; color: #8250df; }
details { margin-top: 4px; color: var(--muted); font-size: 12px; }
details summary { cursor: pointer; }
details ul { margin: 4px 0 0; padding-left: 18px; max-height: 220px; overflow: auto; }
td.img { width: 124px; }
td.img img { width: 112px; display: block; border: 1px solid var(--line); background: #f6f8fa;
             image-rendering: auto; }
td.img .none { display: block; width: 112px; color: #adb5bd; font-size: 12px; text-align: center;
               padding: 30px 0; border: 1px dashed var(--line); }
.bad { color: var(--fail); font-weight: 700; }
.sub { display: block; color: var(--muted); font-size: 11px; }
.sub.bad { color: var(--fail); }
.thr { text-decoration: underline dotted; cursor: help; white-space: nowrap; font-size: 11px; }
.verdict { display: inline-block; font-weight: 700; font-size: 12px; padding: 2px 8px; border-radius: 10px;
           color: #fff; white-space: nowrap; }
.verdict.pass { background: var(--pass); } .verdict.fail { background: var(--fail); }
.verdict.error { background: var(--err); } .verdict.no-reference { background: var(--noref); }
.verdict.unsupported, .verdict.known-quirk { background: var(--noref); }
pre.err { white-space: pre-wrap; word-break: break-word; margin: 0; color: #82071e; max-width: 640px; }
.note { color: var(--err); font-size: 12px; margin-top: 4px; }
footer { margin-top: 24px; color: var(--muted); font-size: 12px; }
"#;

const SCRIPT: &str = r#"
(function () {
  var rows = Array.prototype.slice.call(document.querySelectorAll('tr.row'));
  var buttons = Array.prototype.slice.call(document.querySelectorAll('.filters button'));
  var search = document.getElementById('search');
  var filter = 'all';
  function apply() {
    var q = search.value.trim().toLowerCase();
    rows.forEach(function (r) {
      var v = r.getAttribute('data-verdict');
      var ok = filter === 'all' || (filter === 'problems' && (v === 'fail' || v === 'error')) || filter === v;
      r.hidden = !(ok && (!q || r.getAttribute('data-label').indexOf(q) >= 0));
    });
  }
  buttons.forEach(function (b) {
    b.addEventListener('click', function () {
      filter = b.getAttribute('data-filter');
      buttons.forEach(function (o) { o.classList.toggle('on', o === b); });
      apply();
    });
  });
  search.addEventListener('input', apply);
  Array.prototype.slice.call(document.querySelectorAll('a[data-q]')).forEach(function (a) {
    a.addEventListener('click', function (e) { e.preventDefault(); search.value = a.getAttribute('data-q'); apply(); });
  });
})();
"#;

/// The report as an HTML page.
pub fn to_html(report: &Report) -> String {
    let s = &report.summary;
    let mut h = String::with_capacity(64 * 1024);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         <title>luster conformance: {} of {} passed</title>\n<style>{STYLE}</style>\n</head>\n<body>\n",
        s.passed, s.rows
    );
    header(&mut h, report);
    homeworks(&mut h, report);
    let problems = s.failed + s.errored;
    let _ = writeln!(
        h,
        "<div class=\"filters\"><button class=\"on\" data-filter=\"all\">All ({})</button>\
         <button data-filter=\"problems\">Failures and errors ({problems})</button>\
         <button data-filter=\"pass\">Passed ({})</button>\
         <input id=\"search\" type=\"search\" placeholder=\"filter scenes: hw2/, mirror …\"></div>",
        s.rows, s.passed
    );
    h.push_str(
        "<table class=\"results\">\n<thead><tr><th>Scene → image</th><th>Verdict</th><th>Our render</th>\
         <th>Expected</th><th>LDR-FLIP heatmap</th><th>PSNR</th><th>SSIM</th><th>FLIP</th>\
         <th>Differing</th><th>Time</th><th>Threshold</th></tr></thead>\n<tbody>\n",
    );
    for scene in &report.scenes {
        scene_rows(&mut h, scene);
    }
    h.push_str("</tbody>\n</table>\n");
    let _ = writeln!(
        h,
        "<footer>PSNR on 8-bit display values (peak 1; ∞ for identical images). SSIM on luma \
         (Wang et al. 2004). FLIP: mean LDR-FLIP error in [0, 1] (Andersson et al., \
         “FLIP: A Difference Evaluator for Alternating Images”, HPG 2020); the heatmap shows it per \
         pixel, black = no visible difference, yellow = large. “Differing”: pixels whose 8-bit codes \
         differ. Written by {} — the same data is in <a href=\"results.json\">results.json</a>.</footer>",
        escape(&report.generator)
    );
    let _ = write!(h, "<script>{SCRIPT}</script>\n</body>\n</html>\n");
    h
}

fn header(h: &mut String, r: &Report) {
    let s = &r.summary;
    h.push_str("<h1>luster conformance report</h1>\n<p class=\"meta\">");
    let _ = write!(h, "course folder <code>{}</code>", escape(&r.root));
    if let Some(only) = &r.only {
        let _ = write!(h, " · only scenes matching <code>{}</code>", escape(only));
    }
    let _ = writeln!(
        h,
        " · {} scenes, {} images · {} job{} × {} thread{} · {} · {}</p>",
        s.scenes,
        s.rows,
        r.jobs,
        plural(r.jobs),
        r.threads,
        plural(r.threads),
        duration(r.total_seconds),
        escape(&r.generator)
    );
    let _ = write!(
        h,
        "<div class=\"cards\"><div class=\"card pass\"><b>{}</b>passed</div>\
         <div class=\"card fail\"><b>{}</b>failed</div>\
         <div class=\"card error\"><b>{}</b>errored</div>",
        s.passed, s.failed, s.errored
    );
    if s.no_reference > 0 {
        let _ = write!(h, "<div class=\"card noref\"><b>{}</b>no expected image</div>", s.no_reference);
    }
    if s.unsupported > 0 {
        let _ = write!(h, "<div class=\"card noref\"><b>{}</b>unsupported feature</div>", s.unsupported);
    }
    if s.known_quirks > 0 {
        let _ = write!(h, "<div class=\"card noref\"><b>{}</b>known data quirk</div>", s.known_quirks);
    }
    let _ =
        writeln!(h, "<div class=\"card time\"><b>{}</b>total time</div></div>", duration(r.total_seconds));
}

fn homeworks(h: &mut String, r: &Report) {
    h.push_str(
        "<h2>By homework</h2>\n<table class=\"hw\"><thead><tr><th>Homework</th><th>Scenes</th>\
         <th>Images</th><th>Passed</th><th>Failed</th><th>Errored</th><th>Unsupported</th><th>Data quirks</th>\
         <th></th><th>Time</th></tr></thead>\n<tbody>",
    );
    for hw in &r.homeworks {
        let q = format!("{}/", hw.hw);
        let _ = write!(h, "<tr><td><a href=\"#\" data-q=\"{}\">{}</a></td>", escape(&q), escape(&hw.hw));
        counts_cells(h, &hw.counts);
        let _ = writeln!(h, "<td>{}</td></tr>", duration(hw.seconds));
    }
    h.push_str("</tbody><tfoot><tr><td>All</td>");
    counts_cells(h, &r.summary);
    let _ = writeln!(h, "<td>{}</td></tr></tfoot></table>", duration(r.total_seconds));
}

fn counts_cells(h: &mut String, c: &Counts) {
    let cell = |n: usize, class: &str| {
        if n == 0 {
            "<td class=\"zero\">0</td>".to_string()
        } else {
            format!("<td class=\"{class}\">{n}</td>")
        }
    };
    let _ = write!(
        h,
        "<td>{}</td><td>{}</td>{}{}{}{}{}",
        c.scenes,
        c.rows,
        cell(c.passed, "n-pass"),
        cell(c.failed, "n-fail"),
        cell(c.errored, "n-error"),
        cell(c.unsupported, "n-noref"),
        cell(c.known_quirks, "n-noref")
    );
    let total = c.rows.max(1) as f64;
    let pct = |n: usize| 100.0 * n as f64 / total;
    let _ = write!(
        h,
        "<td><span class=\"bar\" title=\"{:.0}% passed\"><span class=\"p\" style=\"width:{:.2}%\"></span>\
         <span class=\"f\" style=\"width:{:.2}%\"></span><span class=\"e\" style=\"width:{:.2}%\"></span></span></td>",
        pct(c.passed),
        pct(c.passed),
        pct(c.failed),
        pct(c.errored)
    );
}

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

fn scene_rows(h: &mut String, scene: &SceneEntry) {
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
    thumb(h, img.render.as_deref(), img.thumbs.render.as_deref(), "our render", "not rendered");
    thumb(h, img.expected.as_deref(), img.thumbs.expected.as_deref(), "expected image", "no expected image");
    if let (Some(orig), Some(_)) = (&img.expected_original, &img.expected) {
        // EXR/HDR: the thumbnail links to the preview; offer the original too.
        h.truncate(h.len() - "</td>".len());
        let _ = write!(h, "<span class=\"sub\">preview; <a href=\"{}\">original</a></span></td>", url(orig));
    }
    thumb(h, img.heatmap.as_deref(), img.thumbs.heatmap.as_deref(), "LDR-FLIP heatmap", "no heatmap");
    match &img.metrics {
        Some(m) => {
            let psnr = match m.psnr {
                Some(p) => format!("{p:.2} dB"),
                None => "∞ dB".to_string(),
            };
            let bad = |ok: bool| if ok { "num" } else { "num bad" };
            let _ = write!(
                h,
                "<td class=\"{}\">{psnr}</td><td class=\"num\">{:.4}</td><td class=\"{}\">{:.4}</td>",
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
    let _ = write!(
        h,
        "<td class=\"num\" title=\"load and build {}\">{}</td>",
        seconds(scene.setup_seconds),
        seconds(img.seconds)
    );
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
    // The bias test on 8×8 block means: the z-scores, red when missed.
    let coarse = match (t.max_mean_z2, t.max_outliers, img.metrics.as_ref()) {
        (Some(max_z2), Some(max_out), Some(m)) => format!(
            "<span class=\"sub{}\">8×8 z² {} ≤ {max_z2}, |z|&gt;5 {} ≤ {:.1}%</span>",
            if m.z_ok { "" } else { " bad" },
            m.block_mean_z2.map(|z| format!("{z:.2}")).unwrap_or_else(|| "–".to_string()),
            m.block_outliers.map(|o| format!("{:.2}%", o * 100.0)).unwrap_or_else(|| "–".to_string()),
            max_out * 100.0
        ),
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
    let _ = write!(
        h,
        "<td><span class=\"thr\" title=\"{}\">PSNR ≥ {:.2}<br>FLIP ≤ {:.4}</span>{pair}{coarse}</td>",
        escape(&t.reason),
        t.min_psnr,
        t.max_flip
    );
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

fn seconds(s: f64) -> String {
    format!("{s:.2} s")
}

fn duration(s: f64) -> String {
    if s < 60.0 {
        format!("{s:.1} s")
    } else {
        format!("{}:{:04.1} min", (s / 60.0).floor() as u64, s % 60.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_and_quotes() {
        assert_eq!(escape("<a href=\"x\">&'"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
    }

    #[test]
    fn urls_are_percent_encoded_then_escaped() {
        assert_eq!(url("renders/a b#1.png"), "renders/a%20b%231.png");
        assert_eq!(url("x/\"<y>.png"), "x/%22%3Cy%3E.png");
        assert_eq!(url("ü.png"), "%C3%BC.png");
    }

    #[test]
    fn durations_read_well() {
        assert_eq!(duration(12.34), "12.3 s");
        assert_eq!(duration(125.0), "2:05.0 min");
    }
}
