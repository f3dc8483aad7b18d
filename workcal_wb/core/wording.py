"""Messages from core worded for people inside FreeCAD (the panels, the Report view): the command
line's flags taken out or said as words, numbers with float noise rounded."""
import re


def for_people(text: str) -> str:
    """``text`` without command-line flags (``(--force)``, ``--model-units m``: taken out, or replaced by
    what they mean) and with numbers such as 70.96000000000001 rounded to four digits."""
    text = re.sub(r"\s*\((?:the CLI's |use |with |see )?--[a-z][\w-]*(?: [\w.-]+)?(?:;[^)]*)?\)", "", text)
    text = re.sub(r"(?<![\w-])--force\b", "forcing", text)
    text = re.sub(r"(?<![\w-])--[a-z][\w-]*-units\b", "unit", text)
    text = re.sub(r"(?<![\w-])--[a-z][\w-]*", lambda m: m.group(0)[2:].replace("-", " "), text)
    return re.sub(r"-?\d+\.\d{5,}", lambda m: f"{float(m.group(0)):.4g}", text)
