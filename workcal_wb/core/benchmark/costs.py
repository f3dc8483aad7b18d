"""What each check's refusals cost, counted over a table's rows: on how many right poses a reason code
fired (and how many it alone kept from "ok"), and how many wrong poses it alone stopped.

A row is anything with ``right`` (the pose is the truth's), ``status`` and ``codes`` (its reasons'
codes in order).  A failing match is not weighed for doubts, so a code can hide those it ends before."""
from __future__ import annotations


def cost_lines(rows: list) -> list[str]:
    """The Markdown table of the checks that fired on a row not "ok", most costly first."""
    refused = [r for r in rows if r.status != "ok"]
    fired = sorted({code for r in refused for code in r.codes})
    if not fired:
        return ["No check refused a pose here.", ""]

    def count(right: bool, code: str, alone: bool) -> int:
        return sum(1 for r in refused if r.right == right and code in r.codes and (not alone or set(r.codes) == {code}))

    counted = [(code, count(True, code, False), count(True, code, True), count(False, code, False),
                count(False, code, True)) for code in fired]
    counted.sort(key=lambda c: (-c[2], -c[1], c[0]))
    lines = ["What each check cost: the reason codes of the poses not \"ok\"; right poses it refused (alone: "
             "the only code, so without it the pose would have been \"ok\") and wrong poses it stopped (alone: "
             "no other check did).", "",
             "| code | right poses refused | of them alone | wrong poses stopped | of them alone |",
             "|---|---|---|---|---|"]
    lines += [f"| `{code}` | {right} | {right_alone} | {wrong} | {wrong_alone} |"
              for code, right, right_alone, wrong, wrong_alone in counted]
    return lines + [""]
