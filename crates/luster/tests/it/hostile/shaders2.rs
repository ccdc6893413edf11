//! Hostile shaders of issue 47: recursion through library functions that
//! would overflow the native stack, library calls that would outrun the time
//! limit, and error messages that would quote a file that is not a shader or
//! reach the terminal raw. Each case runs as its own `luster render` under
//! the checks of [`super::check`] (exit code 2, one `error:` line with the
//! expected words, no crash text, nothing written), and within a time bound
//! of its own.

use std::time::{Duration, Instant};

use super::kit::{shaded, Case};

/// A shader case whose script is `code`, run with `--shader-timeout
/// timeout`, expecting `expect` in the error line.
fn shader(name: &'static str, timeout: &str, code: &str, expect: &[&'static str]) -> Case {
    Case {
        name,
        files: Vec::new(),
        args: ["render", "-q", "--threads", "2", "--shader-timeout", timeout, "-o", "{out}", "s.xml"]
            .map(String::from)
            .to_vec(),
        expect: [&["s.xml: ", "shader 'x'"][..], expect].concat(),
        absent: Vec::new(),
        multiline: false,
    }
    .text("s.xml", shaded("x.lua"))
    .text("x.lua", code.to_string())
}

include!("../../../../shading/tests-data/recursions.rs");

fn recursions() -> Vec<Case> {
    let mut cases = Vec::new();
    for &(name, code) in RECURSIONS {
        for (place, script) in [
            ("at load", format!("{code}\ngo()\nfunction color(s) return 1, 1, 1 end")),
            ("in a call", format!("{code}\nfunction color(s) go() return 1, 1, 1 end")),
            ("in pcall", format!("{code}\nfunction color(s) local ok, e = pcall(go) error(e, 0) end")),
        ] {
            let label: &'static str = Box::leak(format!("recursion: {name}, {place}").into_boxed_str());
            cases.push(shader(label, "10", &script, &["x.lua:", "too deep"]));
        }
    }
    cases
}

/// Cases with the most seconds each may take: library calls that ran for
/// minutes under the limit, and the top level that took twice the limit.
fn slow() -> Vec<(Case, f64)> {
    let big = "local a = string.rep('a', 4e6)\nlocal p = string.rep('a', 2e6) .. 'b'\n";
    let spin = |call: &str| format!("{big}function color(s) while true do {call} end end");
    let limited = |name, code: &str, words: &[&'static str]| shader(name, "1", code, words);
    let time = &["x.lua:", "time limit"][..];
    vec![
        (limited("plain find of megabytes", &spin("a:find(p, 1, true)"), time), 1.6),
        (limited("literal find of megabytes", &spin("string.find(a, p)"), time), 1.6),
        (limited("literal gsub of megabytes", &spin("a:gsub(p, 'x')"), time), 1.6),
        (limited("literal match of megabytes", &spin("a:match(p)"), time), 1.6),
        (
            limited(
                "table.sort of millions, again and again",
                "local t = {}\nfor i = 1, 3e6 do t[i] = (i * 7919) % 1000003 end\n\
                 function color(s) for k = 1, 100 do table.sort(t) end return 1, 1, 1 end",
                time,
            ),
            2.5,
        ),
        (
            limited("table.move of 2^31 nils", "function color(s) table.move({}, 1, 2^31 - 2, 1) end", time),
            1.6,
        ),
        (
            limited(
                "16 MB concatenations in a loop",
                "local x = string.rep('x', 1.6e7)\nfunction color(s) while true do local y = x .. x end end",
                time,
            ),
            1.6,
        ),
        (limited("endless loop at load, limit 1 s", "while true do end", time), 1.35),
    ]
}

/// Error messages: a file that is not a shader, control characters, size.
fn messages() -> Vec<(Case, usize)> {
    let key = "-----BEGIN OPENSSH PRIVATE KEY-----\n\
               b3BlbnNzaC1rZXktdjEAAAAABG5vbmUAAAAEbm9uZQAAAAAAAAABAAAAMwAAAAtzc2gtZW\n\
               QyNTUxOQAAACDtMZsGcm4NNZNdg6jkcwZ1mk6ArTTCQb7Sxhj7eSDeZBAAAAJgAAAAAAA\n\
               -----END OPENSSH PRIVATE KEY-----\n";
    vec![
        (
            shader("a private key as a shader", "1", key, &["x.lua:3", "a token of"])
                .absent(&["b3Blbn", "QyNTUx", "AAAA", "PRIVATE", "BEGIN"]),
            1000,
        ),
        (
            shader(
                "error with ESC, BEL and CR",
                "1",
                "error('\\27]0;pwned\\7 and\\rCR')",
                &["x.lua:1", "\\e]0;pwned"],
            )
            .absent(&["\u{1b}", "\u{7}", "\r"]),
            1000,
        ),
        (
            shader("error of 16 MiB", "5", "error(string.rep('x', 16e6))", &["x.lua:1", "more characters"]),
            3000,
        ),
    ]
}

#[test]
fn hostile_shaders_of_issue_47_end_cleanly_and_promptly() {
    let mut timed: Vec<(Case, f64)> = recursions().into_iter().map(|c| (c, 5.0)).collect();
    timed.extend(slow());
    let sized = messages();
    // One at a time: the time bounds are measured, and two cases would
    // share the cores.
    let mut failures = Vec::new();
    for (case, bound) in &timed {
        let start = Instant::now();
        let problem = super::check(case);
        let took = start.elapsed();
        failures.extend(problem);
        if took > Duration::from_secs_f64(*bound) {
            failures.push(format!("{}: took {took:.2?}, more than {bound} s", case.name));
        }
    }
    for (case, most) in &sized {
        failures.extend(super::check(case));
        let root = tempfile::tempdir().expect("a temporary folder");
        case.materialize(root.path());
        std::fs::create_dir(root.path().join("out")).expect("the output folder");
        let args: Vec<String> = case.args.iter().map(|a| a.replace("{out}", "out")).collect();
        let run = super::luster(&args, root.path());
        if run.stderr.len() > *most {
            failures.push(format!(
                "{}: {} bytes of error output, more than {most}",
                case.name,
                run.stderr.len()
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} hostile shader cases misbehaved:\n{}",
        failures.len(),
        failures.join("\n")
    );
}
