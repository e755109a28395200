// The Code tab's editor: CodeMirror 6 with Python or Octave highlighting, Ctrl/Cmd+S to save,
// read-only when this browser may not edit, and the line of the file's error marked. Loaded
// with a dynamic import (CodePanel), so CodeMirror is not in the page's first chunk.
//
// The document belongs to the editor: it reports every change (onChange) and takes a text
// from outside only when `docSeq` or the file changes (opened, reloaded from disk).

import { useEffect, useRef } from "react";
import { closeBrackets, closeBracketsKeymap } from "@codemirror/autocomplete";
import { defaultKeymap, history, historyKeymap, indentWithTab } from "@codemirror/commands";
import { python } from "@codemirror/lang-python";
import { bracketMatching, HighlightStyle, indentOnInput, indentUnit, StreamLanguage, syntaxHighlighting } from "@codemirror/language";
import { octave } from "@codemirror/legacy-modes/mode/octave";
import { highlightSelectionMatches, searchKeymap } from "@codemirror/search";
import { Compartment, EditorState, Prec, StateEffect, StateField, type Extension } from "@codemirror/state";
import {
  Decoration,
  drawSelection,
  EditorView,
  highlightActiveLine,
  highlightActiveLineGutter,
  highlightSpecialChars,
  keymap,
  lineNumbers,
  type DecorationSet,
} from "@codemirror/view";
import { tags as t } from "@lezer/highlight";

export interface CodeEditorProps {
  /** The file shown ("pass_drill.py"). */
  name: string;
  /** Changes when the text must be taken from `getText` (opened, reloaded from disk). */
  docSeq: number;
  getText: () => string;
  language: "python" | "octave";
  readOnly: boolean;
  /** 1-based line of the file's error (marked, scrolled into view when it appears), or null. */
  errorLine: number | null;
  onChange: (text: string) => void;
  onSave: () => void;
}

/** What an editor for a short team file needs (CodeMirror's basicSetup without completion
 * pop-ups, lint and folding: less to load, nothing popping up while a student types). Tab
 * indents; Esc then Tab leaves the editor. */
const setup: Extension = [
  lineNumbers(),
  highlightActiveLineGutter(),
  highlightSpecialChars(),
  history(),
  drawSelection(),
  indentOnInput(),
  bracketMatching(),
  closeBrackets(),
  highlightActiveLine(),
  highlightSelectionMatches(),
  EditorState.tabSize.of(4),
  // the panel is narrow beside the field: long lines wrap instead of scrolling sideways
  EditorView.lineWrapping,
  keymap.of([...closeBracketsKeymap, ...defaultKeymap, ...searchKeymap, ...historyKeymap, indentWithTab]),
];

/** Colours for the page's dark panel (the default highlight style is made for white). */
const darkHighlight = HighlightStyle.define([
  { tag: [t.keyword, t.controlKeyword, t.definitionKeyword, t.moduleKeyword, t.operatorKeyword], color: "#c792ea" },
  { tag: [t.string, t.special(t.string)], color: "#c3e88d" },
  { tag: [t.number, t.bool, t.null], color: "#f78c6c" },
  { tag: [t.comment, t.lineComment, t.blockComment], color: "#7f8ea3", fontStyle: "italic" },
  { tag: [t.function(t.variableName), t.function(t.definition(t.variableName))], color: "#82aaff" },
  { tag: [t.definition(t.variableName), t.className, t.definition(t.className)], color: "#ffcb6b" },
  { tag: [t.propertyName], color: "#89ddff" },
  { tag: [t.operator, t.punctuation, t.bracket], color: "#cbd5e1" },
  { tag: [t.self, t.atom, t.standard(t.variableName)], color: "#ff9cac" },
  { tag: t.invalid, color: "#f87171" },
]);

const theme = EditorView.theme(
  {
    "&": { backgroundColor: "#0b1220", color: "#e5e7eb", fontSize: "13px", height: "100%" },
    ".cm-content": { fontFamily: "ui-monospace, SFMono-Regular, Menlo, Consolas, monospace", caretColor: "#f8fafc" },
    ".cm-scroller": { fontFamily: "ui-monospace, SFMono-Regular, Menlo, Consolas, monospace", lineHeight: "1.45" },
    ".cm-gutters": { backgroundColor: "#111a2e", color: "#64748b", border: "none", borderRight: "1px solid #24314f" },
    ".cm-activeLine": { backgroundColor: "rgba(148,163,184,0.07)" },
    ".cm-activeLineGutter": { backgroundColor: "rgba(148,163,184,0.12)" },
    "&.cm-focused .cm-cursor": { borderLeftColor: "#f8fafc" },
    "&.cm-focused .cm-selectionBackground, .cm-selectionBackground, ::selection": { backgroundColor: "rgba(96,165,250,0.35) !important" },
    ".cm-error-line": { backgroundColor: "rgba(220,38,38,0.28)", boxShadow: "inset 3px 0 0 #f87171" },
    ".cm-panels": { backgroundColor: "#16213a", color: "#e5e7eb" },
    ".cm-tooltip": { backgroundColor: "#16213a", color: "#e5e7eb", border: "1px solid #24314f" },
    ".cm-matchingBracket": { backgroundColor: "rgba(96,165,250,0.25)", outline: "none" },
  },
  { dark: true },
);

const setErrorLine = StateEffect.define<number | null>();
const errorLineDeco = Decoration.line({ class: "cm-error-line", attributes: { "data-error-line": "true" } });

/** The marked error line, moved along with the edits made after it was marked. */
const errorField = StateField.define<DecorationSet>({
  create: () => Decoration.none,
  update(deco, tr) {
    deco = deco.map(tr.changes);
    for (const e of tr.effects) {
      if (!e.is(setErrorLine)) continue;
      const n = e.value;
      if (n === null || n < 1 || n > tr.state.doc.lines) deco = Decoration.none;
      else deco = Decoration.set([errorLineDeco.range(tr.state.doc.line(n).from)]);
    }
    return deco;
  },
  provide: (f) => EditorView.decorations.from(f),
});

/** The language and its indentation: Python's four spaces (PEP 8; CodeMirror's default of two
 * makes the next line after a `def` an "unexpected indent"), two in Octave as in team/*.m. */
function languageExt(language: "python" | "octave"): Extension {
  return language === "octave"
    ? [StreamLanguage.define(octave), indentUnit.of("  ")]
    : [python(), indentUnit.of("    ")];
}

function readOnlyExt(ro: boolean): Extension {
  return [EditorState.readOnly.of(ro), EditorView.editable.of(!ro)];
}

export default function CodeEditor(props: CodeEditorProps) {
  const host = useRef<HTMLDivElement>(null);
  const view = useRef<EditorView | null>(null);
  const langC = useRef(new Compartment()).current;
  const roC = useRef(new Compartment()).current;
  // the latest callbacks, for the extensions made once
  const cb = useRef(props);
  cb.current = props;

  const makeState = (text: string, p: CodeEditorProps) =>
    EditorState.create({
      doc: text,
      extensions: [
        Prec.highest(
          keymap.of([
            {
              key: "Mod-s",
              preventDefault: true,
              run: () => {
                cb.current.onSave();
                return true;
              },
            },
          ]),
        ),
        setup,
        syntaxHighlighting(darkHighlight),
        theme,
        langC.of(languageExt(p.language)),
        roC.of(readOnlyExt(p.readOnly)),
        errorField,
        EditorView.updateListener.of((u) => {
          if (u.docChanged) cb.current.onChange(u.state.doc.toString());
        }),
        EditorView.contentAttributes.of({ "aria-label": `Source of ${p.name}`, "data-testid": "code-editor-content" }),
      ],
    });

  // one view for the component's life; a new state for every file or reload
  useEffect(() => {
    if (!host.current) return;
    const v = new EditorView({ state: makeState(cb.current.getText(), cb.current), parent: host.current });
    view.current = v;
    return () => {
      v.destroy();
      view.current = null;
    };
  }, []);

  const docKey = `${props.name}#${props.docSeq}`;
  const lastDoc = useRef(docKey);
  useEffect(() => {
    const v = view.current;
    if (!v || lastDoc.current === docKey) return;
    lastDoc.current = docKey;
    v.setState(makeState(props.getText(), props));
    v.dispatch({ effects: setErrorLine.of(props.errorLine) });
  }, [docKey]);

  useEffect(() => {
    view.current?.dispatch({ effects: langC.reconfigure(languageExt(props.language)) });
  }, [props.language, langC]);

  useEffect(() => {
    view.current?.dispatch({ effects: roC.reconfigure(readOnlyExt(props.readOnly)) });
  }, [props.readOnly, roC]);

  useEffect(() => {
    const v = view.current;
    if (!v) return;
    const n = props.errorLine;
    const effects: StateEffect<unknown>[] = [setErrorLine.of(n)];
    if (n !== null && n >= 1 && n <= v.state.doc.lines) effects.push(EditorView.scrollIntoView(v.state.doc.line(n).from, { y: "center" }));
    v.dispatch({ effects });
  }, [props.errorLine, docKey]);

  return <div className="code-editor" ref={host} data-testid="code-editor" data-file={props.name} data-readonly={props.readOnly ? "true" : "false"} />;
}
