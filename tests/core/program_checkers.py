"""Strict checkers of the documented rules of each controller language, kept small, for the tests.

Each ``check_*`` raises AssertionError naming the line and the rule a program breaks.  Every program is
plain ASCII (UR's script interface takes only ASCII text, Fanuc TP and CNC posts write ASCII).  They follow:
KRL: the krl.g4 grammar's module structure (``&`` header lines, then DEF on the first line, EXT
declarations before statements, END), names of at most 24 characters, statements of the forms
WorkCal writes (a PTP to a POS with Status 0..7 and Turn 0..63); RAPID: MODULE/ENDMODULE,
declarations before routines, no PROC main, every used tool/work object/speed/zone declared,
identifiers of at most 32 characters, strings of at most 80; URScript: ``def`` in the first column
on the first line, every line up to ``end`` indented, ``halt`` a keyword (no ``halt()``); Fanuc LS:
/PROG /ATTR /MN /POS /END, ``NNNN:`` lines with the motion letter right after the colon, remarks of
at most 32 characters, every P[] used defined, LINE_COUNT true, at most 9999 lines;
G-code: one word grammar (letter + number), comments without ``(`` ``;`` ``%`` inside, ``%`` only
as the first and last line, at most one code of each modal group per block, G43/G43.4 H only in a block
that moves Z (on Fanuc-family controls the offset itself moves Z).
"""
import re

IDENT = r"[A-Za-z_$][A-Za-z0-9_$]*"
NUMBER = r"-?\d+(?:\.\d+)?"
AGGREGATE = r"\{X N, Y N, Z N, A N, B N, C N\}".replace("N", NUMBER)
# A POS: the frame with Status and Turn (whole numbers, Status 0..7, Turn 0..63)
POS = r"\{X N, Y N, Z N, A N, B N, C N, S [0-7], T (?:[0-9]|[1-5][0-9]|6[0-3])\}".replace("N", NUMBER)
KRL_STATEMENTS = [rf"BAS\(#\w+, {NUMBER}\)", rf"\$BASE = \$ROBROOT(?::{AGGREGATE})?", rf"\$APO\.CDIS = {NUMBER}",
                  rf"\$VEL\.CP = {NUMBER}", "PTP XHOME", rf"PTP {AGGREGATE}", rf"PTP {POS}", rf"LIN {AGGREGATE}( C_DIS)?",
                  "HALT",
                  rf"WAIT SEC {NUMBER}", r"IF .* THEN", "ENDIF", rf"{IDENT}\( \)"]


def check_ascii(text: str) -> None:
    bad = next((number for number, line in enumerate(text.split("\n"), start=1) if not line.isascii()), None)
    assert bad is None, f"line {bad}: not ASCII"


def check_krl(text: str, name: str) -> None:
    check_ascii(text)
    lines = text.split("\n")
    assert lines[-1] == "", "the file ends with a newline"
    body = [line for line in lines[:-1] if not line.startswith("&")]
    assert all(line.startswith("&") for line in lines[:len(lines) - 1 - len(body)]), "& lines only at the top"
    assert re.fullmatch(rf"DEF ({IDENT})\( \)", body[0]), f"line 1 after the & lines must be DEF: {body[0]!r}"
    assert re.fullmatch(rf"DEF {name}\( \)", body[0]) and len(name) <= 24, "DEF name = file name, <= 24 characters"
    assert body[-1] == "END", "the module ends with END"
    declarations = True
    for number, line in enumerate(body[1:-1], start=2):
        if line.startswith(";") or not line.strip():
            continue
        if line.startswith("EXT "):
            assert declarations, f"line {number}: EXT after a statement"
            assert re.fullmatch(rf"EXT {IDENT} \({IDENT} :IN(, {IDENT} :IN)*\)", line), f"line {number}: {line}"
            continue
        declarations = False
        assert any(re.fullmatch(s, line) for s in KRL_STATEMENTS), f"line {number}: not a KRL statement: {line!r}"


def check_rapid(text: str, known=()) -> None:
    """``known``: data declared in another module of the program (the main module of parts)."""
    check_ascii(text)
    lines = text.rstrip("\n").split("\n")
    assert re.fullmatch(rf"MODULE ({IDENT})", lines[0]) and lines[-1] == "ENDMODULE", "MODULE ... ENDMODULE"
    declared, in_proc = set(known), False
    for number, line in enumerate(lines[1:-1], start=2):
        code = line.strip()
        assert len(re.findall(r'"[^"]*"', code)) == code.count('"') // 2, f"line {number}: unbalanced string"
        assert all(len(s) <= 82 for s in re.findall(r'"[^"]*"', code)), f"line {number}: string over 80"
        if not code or code.startswith("!"):
            continue
        if m := re.fullmatch(rf"(?:PERS|CONST|VAR) (\w+) ({IDENT}) := .*;", code):
            assert not in_proc and len(m.group(2)) <= 32, f"line {number}: declaration"
            declared.add(m.group(2))
        elif m := re.fullmatch(rf"PROC ({IDENT})\(\)", code):
            assert m.group(1).lower() != "main" and len(m.group(1)) <= 32, f"line {number}: PROC {m.group(1)}"
            in_proc = True
        elif code == "ENDPROC":
            in_proc = False
        else:
            assert in_proc and code.endswith((";", "THEN")) or code == "ENDIF", f"line {number}: {code!r}"
            if m := re.match(r"Move[JL] \[.*\], (\w+), (\w+), (\w+)\\WObj:=(\w+);$", code):
                used = {m.group(1), m.group(3), m.group(4)} | ({m.group(2)} - {"fine"})
                assert used <= declared, f"line {number}: {sorted(used - declared)} used but not declared here"


def check_urscript(text: str) -> None:
    check_ascii(text)
    lines = text.rstrip("\n").split("\n")
    assert re.fullmatch(rf"def {IDENT}\(\):", lines[0]), "line 1 must be def name(): in the first column"
    assert lines[-1] == "end", "the last line is end"
    for number, line in enumerate(lines[1:-1], start=2):
        assert line.startswith("  "), f"line {number}: not indented: {line!r}"
        assert not re.match(r"\s*halt\s*\(", line), f"line {number}: halt is a keyword, not a function"


def check_fanuc(text: str, name: str) -> None:
    check_ascii(text)
    lines = text.rstrip("\n").split("\n")
    assert lines[0] == f"/PROG  {name}" and lines[1] == "/ATTR" and lines[-1] == "/END"
    for entry in ("OWNER", "COMMENT", "PROG_SIZE", "CREATE", "MODIFIED", "FILE_NAME", "VERSION", "LINE_COUNT",
                  "MEMORY_SIZE", "PROTECT", "TCD:  STACK_SIZE", "DEFAULT_GROUP", "CONTROL_CODE"):
        assert any(line.startswith(entry) for line in lines[2:lines.index("/MN")]), f"/ATTR lacks {entry}"
    main = lines[lines.index("/MN") + 1:lines.index("/POS")]
    count = int(re.search(r"LINE_COUNT\t= (\d+);", text).group(1))
    assert count == len(main) <= 9999, "LINE_COUNT is the number of /MN lines, at most 9999"
    used = []
    for n, line in enumerate(main, start=1):
        assert re.fullmatch(rf"{n:4d}:(?:[JL] P\[\d+\] .* ;|  .* ;)", line), f"/MN line {n}: {line!r}"
        if "!" in line[:8]:
            assert len(line[7:-2]) <= 32, f"/MN line {n}: remark over 32 characters"
        used += [int(p) for p in re.findall(r"^\s*\d+:[JL] P\[(\d+)\]", line)]
    for config in re.findall(r"CONFIG : '([^']*)'", text):
        assert re.fullmatch(r"[NF] [UD] [TB], -?\d, -?\d, -?\d", config), f"CONFIG {config!r}: not flip elbow base, 3 turns"
    defined = [int(p) for p in re.findall(r"^P\[(\d+)\]\{", text, flags=re.M)]
    assert defined == used == list(range(1, len(used) + 1)), "every P[] used once, defined, numbered from 1"


G_GROUPS = [{0, 1, 2, 3}, {17, 18, 19}, {90, 91}, {20, 21}, {43, 43.4, 49}, {4, 28, 53}]


def check_gcode(text: str) -> None:
    check_ascii(text)
    lines = text.rstrip("\n").split("\n")
    assert lines[0] == "%" and lines[-1] == "%" and "%" not in "".join(lines[1:-1]), "% only around the program"
    for number, line in enumerate(lines[1:-1], start=2):
        comments = re.findall(r"\(([^()]*)\)", line)
        assert all(";" not in c for c in comments), f"line {number}: ';' inside a comment"
        code = re.sub(r"\([^()]*\)", "", line)
        assert "(" not in code and ")" not in code and ";" not in code, f"line {number}: stray comment character"
        assert re.fullmatch(rf"(?:\s*[A-Z]{NUMBER})*\s*", code), f"line {number}: not letter+number words: {line!r}"
        codes = [float(v) for v in re.findall(rf"G({NUMBER})", code)]
        for group in G_GROUPS:
            assert len([c for c in codes if c in group]) <= 1, f"line {number}: two codes of one modal group"
        if {43, 43.4} & set(codes):
            assert re.search(rf"Z{NUMBER}", code), f"line {number}: G43 without a Z move"


def comment_text(text: str) -> str:
    """The program's comment lines (any language) joined into one line of words, for finding phrases."""
    words = []
    for line in text.splitlines():
        m = re.match(r"^\s*(?:\d+:\s*!\s?|[;#!(]\s?)(.*?)\s*[;)]?$", line)
        if m:
            words.append(m.group(1))
    return " ".join(" ".join(words).split())


def rapid_declarations(text: str) -> set:
    return set(re.findall(rf"^\s*(?:PERS|CONST|VAR) \w+ ({IDENT}) :=", text, flags=re.M))
