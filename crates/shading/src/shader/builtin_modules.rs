//! Lua modules built into luster, which `require` falls back to when no
//! folder on the search path has a file of that name (so a scene's own
//! `patterns.lua` still wins). They run like any module: instrumented for
//! the time limit, in their own sandboxed environment.

/// `require "patterns"`: POV-Ray's patterns and warps, each with a filtered
/// form (`docs/patterns.md`).
const PATTERNS: &str = include_str!("lib/patterns.lua");

/// The built-in modules by name.
const BUILTIN: &[(&str, &str)] = &[("patterns", PATTERNS)];

/// The source of the built-in module `name`, if there is one.
pub(crate) fn source(name: &str) -> Option<&'static str> {
    BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, code)| *code)
}

/// How messages name a built-in module's file.
pub(crate) fn shown(name: &str) -> String {
    format!("(built-in) {name}.lua")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_ins_are_found_by_their_exact_name_only() {
        assert!(source("patterns").is_some_and(|c| c.contains("M.warp")));
        for other in ["Patterns", "lib.patterns", "patterns.lua", "pattern", ""] {
            assert!(source(other).is_none(), "{other}");
        }
    }
}
