// The shader editor of the `luster watch` page, bundled by build.sh into
// crates/luster/src/watch/editor.js (a global `LusterEditor`).
import { EditorView, keymap, lineNumbers, highlightActiveLine, highlightActiveLineGutter,
  drawSelection, highlightSpecialChars } from "@codemirror/view";
import { EditorState } from "@codemirror/state";
import { StreamLanguage, bracketMatching, indentOnInput, syntaxHighlighting,
  defaultHighlightStyle } from "@codemirror/language";
import { lua } from "@codemirror/legacy-modes/mode/lua";
import { defaultKeymap, history, historyKeymap, indentWithTab } from "@codemirror/commands";
import { searchKeymap, highlightSelectionMatches } from "@codemirror/search";
import { closeBrackets, closeBracketsKeymap } from "@codemirror/autocomplete";
import { lintGutter, setDiagnostics } from "@codemirror/lint";
import { oneDark } from "@codemirror/theme-one-dark";

// An editor in `parent` showing `doc`. `onSave()` runs on Ctrl/Cmd-S,
// `onChange(programmatic)` after every edit.
export function create(parent, doc, { onSave, onChange }) {
  const save = { key: "Mod-s", preventDefault: true, run: () => { if (onSave) onSave(); return true; } };
  return new EditorView({
    parent,
    state: EditorState.create({
      doc,
      extensions: [
        lineNumbers(), highlightActiveLineGutter(), highlightSpecialChars(), history(), drawSelection(),
        indentOnInput(), bracketMatching(), closeBrackets(), highlightActiveLine(),
        highlightSelectionMatches(), StreamLanguage.define(lua),
        syntaxHighlighting(defaultHighlightStyle, { fallback: true }), oneDark, lintGutter(),
        keymap.of([save, ...closeBracketsKeymap, ...defaultKeymap, ...searchKeymap, ...historyKeymap,
          indentWithTab]),
        EditorView.updateListener.of((u) => { if (u.docChanged && onChange) onChange(); }),
        EditorView.theme({ "&": { height: "100%", fontSize: "13px" }, ".cm-scroller": { overflow: "auto" } }),
      ],
    }),
  });
}

// Marks `marks` ([{line, message}], lines from 1) as errors, replacing the
// previous marks; lines past the end are left out. The marks move with
// later edits.
export function mark(view, marks) {
  const doc = view.state.doc;
  const out = [];
  for (const d of marks) {
    if (d.line < 1 || d.line > doc.lines) continue;
    const line = doc.line(d.line);
    out.push({ from: line.from, to: line.to, severity: "error", message: d.message });
  }
  view.dispatch(setDiagnostics(view.state, out));
}

// Replaces the whole text (a file loaded from the server).
export function setText(view, text) {
  view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: text } });
}

export { EditorView };
