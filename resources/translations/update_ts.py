"""Regenerate workcal.ts, the Qt Linguist template of every user-visible WorkCal string.

Debian's FreeCAD has no pylupdate/lupdate, so this script does lupdate's job for Python sources: it
collects the literal arguments of ``translate("context", "text")`` and
``QT_TRANSLATE_NOOP("context", "text")`` calls in workcal_wb/ and writes them as a Qt TS 2.1 file.

    /usr/bin/python3 resources/translations/update_ts.py

Translators copy workcal.ts to workcal_<lang>.ts (e.g. workcal_de.ts), translate it in Qt Linguist and
compile it with ``lrelease workcal_de.ts`` into workcal_de.qm beside it; the workbench registers this
folder with ``FreeCADGui.addLanguagePath`` so FreeCAD loads the .qm of its current language.
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path
from xml.sax.saxutils import escape

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
SOURCES = ROOT / "workcal_wb"
FUNCTIONS = {"translate", "QT_TRANSLATE_NOOP"}


def _name(func) -> str | None:
    if isinstance(func, ast.Name):
        return func.id
    if isinstance(func, ast.Attribute):
        return func.attr
    return None


def messages(root: Path = SOURCES) -> dict:
    """{context: {source text: [(relative file, line), ...]}} in file order."""
    found: dict = {}
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Call) and _name(node.func) in FUNCTIONS and len(node.args) >= 2):
                continue
            context, text = node.args[:2]
            if not (isinstance(context, ast.Constant) and isinstance(context.value, str)
                    and isinstance(text, ast.Constant) and isinstance(text.value, str)):
                continue  # computed strings cannot be translated by lookup
            where = (path.relative_to(ROOT).as_posix(), node.lineno)
            found.setdefault(context.value, {}).setdefault(text.value, []).append(where)
    return found


def ts_document(found: dict) -> str:
    lines = ['<?xml version="1.0" encoding="utf-8"?>', "<!DOCTYPE TS>", '<TS version="2.1">']
    for context in sorted(found):
        lines += ["<context>", f"    <name>{escape(context)}</name>"]
        for text, places in sorted(found[context].items(), key=lambda item: item[1][0]):
            lines.append("    <message>")
            for file, line in places:
                lines.append(f'        <location filename="../../{escape(file)}" line="{line}"/>')
            lines += [f"        <source>{escape(text)}</source>",
                      '        <translation type="unfinished"></translation>', "    </message>"]
        lines.append("</context>")
    lines.append("</TS>")
    return "\n".join(lines) + "\n"


def main() -> int:
    found = messages()
    target = HERE / "workcal.ts"
    target.write_text(ts_document(found), encoding="utf-8")
    print(f"{target}: {sum(len(v) for v in found.values())} strings in {len(found)} contexts")
    return 0


if __name__ == "__main__":
    sys.exit(main())
