//! Checking the scene's `<Parameter>`s against a script that does not
//! declare its parameters with `params{...}` (the prelude checks those that
//! do, with types).
//!
//! Such a script reads `param.NAME`; a scene parameter whose name it never
//! mentions is a typo (`frequncy`) that would otherwise be silently ignored.
//! The names are found in the source text. A script that reads `param` any
//! other way (`param[k]`, `pairs(param)`) may use any name, so it is not
//! checked.

use super::ShaderSource;

/// The names a script reads as `param.NAME` or `param["NAME"]`, or `None`
/// when it uses `param` in a way the text cannot resolve.
pub(crate) fn names_read(code: &str) -> Option<Vec<String>> {
    let bytes = code.as_bytes();
    let ident = |b: u8| b.is_ascii_alphanumeric() || b == b'_';
    let mut names = Vec::new();
    let mut from = 0;
    while let Some(at) = code[from..].find("param").map(|i| i + from) {
        let end = at + "param".len();
        from = end;
        let before = at.checked_sub(1).map(|i| bytes[i]);
        if before.is_some_and(|b| ident(b) || b == b'.' || b == b':')
            || bytes.get(end).is_some_and(|&b| ident(b))
        {
            continue;
        }
        let rest = code[end..].trim_start();
        if let Some(field) = rest.strip_prefix('.') {
            let field = field.trim_start();
            let len = field.bytes().take_while(|&b| ident(b)).count();
            if len == 0 {
                return None;
            }
            names.push(field[..len].to_string());
        } else if let Some(index) = rest.strip_prefix('[') {
            let index = index.trim_start();
            let quote = index.chars().next().filter(|c| *c == '"' || *c == '\'')?;
            let close = index[1..].find(quote)?;
            names.push(index[1..1 + close].to_string());
        } else {
            return None;
        }
    }
    Some(names)
}

/// Fails with a sentence when the scene gives a parameter the script never
/// reads.
pub(crate) fn check_undeclared(src: &ShaderSource) -> Result<(), String> {
    let Some(read) = names_read(&src.code) else { return Ok(()) };
    let mut known: Vec<&str> = read.iter().map(String::as_str).collect();
    known.sort_unstable();
    known.dedup();
    for (name, _) in &src.params {
        if !known.contains(&name.as_str()) {
            let list = if known.is_empty() {
                "none".to_string()
            } else {
                known.iter().map(|n| format!("param.{n}")).collect::<Vec<_>>().join(", ")
            };
            return Err(format!(
                "the scene's parameter '{name}' is never read by the script (it reads {list}); \
                 declare parameters with params{{...}} to have their types checked too"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_are_found_and_other_uses_stop_the_check() {
        let code = "local f = param.frequency or 4\nlocal t = param [ 'tint' ]\nlocal w = param. warp";
        assert_eq!(names_read(code).unwrap(), ["frequency", "tint", "warp"]);
        assert_eq!(names_read("x.param = 1; myparam.z = 2; params{}").unwrap(), Vec::<String>::new());
        assert_eq!(names_read("for k in pairs(param) do end"), None);
        assert_eq!(names_read("local v = param[k]"), None);
    }

    #[test]
    fn a_misspelt_parameter_is_an_error_listing_what_the_script_reads() {
        let src = ShaderSource::new("m", "m.lua", "local f = param.frequency\nlocal w = param.warp")
            .with_number("frequncy", 3.0);
        let e = check_undeclared(&src).unwrap_err();
        assert!(e.contains("'frequncy'") && e.contains("param.frequency, param.warp"), "{e}");
        let ok = ShaderSource::new("m", "m.lua", "local f = param.frequency").with_number("frequency", 3.0);
        assert!(check_undeclared(&ok).is_ok());
    }
}
