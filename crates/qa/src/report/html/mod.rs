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
//! through [`escape`]; paths go through [`url`] as well. The rows are
//! `rows`; the style sheet and the script, `style`.

mod rows;
mod style;

use super::{Counts, Report};
use rows::scene_rows;
use std::fmt::Write;
use style::{SCRIPT, STYLE};

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

pub(super) fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}

pub(super) fn seconds(s: f64) -> String {
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
