//! Hostile cases for what reaches the terminal and the output folder: image
//! names and file names holding control characters, and a film too large for
//! the memory the process may use.

use super::kit::{json, xml, Case, JSON_SPHERE};

/// Cases that must end with one clean error line.
pub fn names() -> Vec<Case> {
    let r = Case::render;
    let esc_json = json(JSON_SPHERE).replace("\"out.png\"", "\"a\\u001b]0;pwned\\u0007.png\"");
    let newline_json = json(JSON_SPHERE).replace("\"out.png\"", "\"a\\nerror: forged.png\"");
    vec![
        // A terminal escape in `ImageName` would retitle the window when printed.
        r("ImageName with an escape (JSON)", "s.json", &["s.json", "<ImageName>", "control character"])
            .text("s.json", esc_json)
            .absent(&["\u{1b}", "\u{7}"]),
        // A newline in a name forges lines in every listing that shows it.
        r("ImageName with a newline (JSON)", "s.json", &["s.json", "<ImageName>", "control character"])
            .text("s.json", newline_json),
        r("ImageName with a newline (XML)", "s.xml", &["s.xml", "<ImageName>", "control character"])
            .text("s.xml", xml("", "").replace("<ImageName>out.png", "<ImageName>a&#10;b.png")),
        r("ImageName with a backslash", "s.xml", &["s.xml", "<ImageName>", "backslash"])
            .text("s.xml", xml("", "").replace("<ImageName>out.png", "<ImageName>a\\b.png")),
        // The scene's own file name is printed in its error: escaped.
        r("scene named with an escape", "bad\u{1b}[2J.xml", &["bad\\e[2J.xml", "line 1"])
            .text("bad\u{1b}[2J.xml", "<Scene><Cameras>")
            .absent(&["\u{1b}"]),
    ]
}
