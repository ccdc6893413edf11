//! Percent-escapes (`%20` for a space) in URIs: a glTF file's relative
//! buffer and image URIs, the watch server's request paths.

/// `s` with its `%XX` escapes decoded; `None` when an escape is malformed
/// (not two hex digits) or the result is not UTF-8.
pub fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b.get(i + 1..i + 3).filter(|h| h.iter().all(u8::is_ascii_hexdigit))?;
            out.push(u8::from_str_radix(std::str::from_utf8(hex).ok()?, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::percent_decode;

    #[test]
    fn escapes_decode_and_malformed_ones_are_refused() {
        assert_eq!(percent_decode("my%20tex%C3%A9.png").as_deref(), Some("my texé.png"));
        assert_eq!(percent_decode("sh%2Fwood%20grain.lua").as_deref(), Some("sh/wood grain.lua"));
        assert_eq!(percent_decode("plain.png").as_deref(), Some("plain.png"));
        // `from_str_radix` alone would take "+1" as a number.
        for bad in ["%", "%2", "bad%zz.png", "%+1", "%ff.png"] {
            assert_eq!(percent_decode(bad), None, "{bad}");
        }
    }
}
