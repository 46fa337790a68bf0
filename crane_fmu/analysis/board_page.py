"""The scoreboard as one self-contained web page: ``OUT/index.html``.

The page is scoreboard.md (its tables, targets, statistics and provenance) turned into HTML, with the
pictures (``summary.png``, with the confidence intervals as error bars, and the S1, S2, S7 runs) and the S2
animations inline as data URIs: one file that opens in a browser with no server and no other file.
"""

import base64
import html
import re
from pathlib import Path

STYLE = """
body { font-family: system-ui, sans-serif; margin: 1.5em auto; max-width: 1500px; padding: 0 1em; color: #222; }
h1 { font-size: 1.6em; } h2 { font-size: 1.2em; margin-top: 2em; border-bottom: 1px solid #ccc; }
.scroll { overflow-x: auto; margin: 0.8em 0; }
table { border-collapse: collapse; font-size: 0.85em; }
th, td { border: 1px solid #999; padding: 0.25em 0.5em; text-align: left; vertical-align: top; }
th { background: #e8eef4; } tr:nth-child(even) td { background: #f6f8fa; }
code { background: #eef; padding: 0 0.2em; }
figure { margin: 1em 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: 0.85em; color: #555; }
.animations { display: flex; flex-wrap: wrap; gap: 1em; }
"""


def _inline(text):
    """Markdown's inline marks of the board (`code`, **bold**, *italic*) as HTML, the rest escaped."""
    text = html.escape(text, quote=False)
    text = re.sub(r"`([^`]+)`", r"<code>\1</code>", text)
    text = re.sub(r"\*\*([^*]+)\*\*", r"<strong>\1</strong>", text)
    return re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"<em>\1</em>", text)


def _cells(line):
    """A table row's cells: split at every ``|`` but an escaped one (``\\|``, which stays in its cell as ``|``)."""
    inner = line.strip().removeprefix("|").removesuffix("|")
    return [c.strip().replace("\\|", "|") for c in re.split(r"(?<!\\)\|", inner)]


def markdown_to_html(text):
    """The markdown the board is written in (headings, paragraphs, lists, tables) as HTML."""
    out, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("|") and i + 1 < len(lines) and re.fullmatch(r"\|(\s*-+\s*\|)+", lines[i + 1].strip()):
            head, body = _cells(line), []
            i += 2
            while i < len(lines) and lines[i].startswith("|"):
                body.append(_cells(lines[i]))
                i += 1
            rows = "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in row) + "</tr>" for row in body)
            out.append('<div class="scroll"><table><thead><tr>' + "".join(f"<th>{_inline(c)}</th>" for c in head)
                       + f"</tr></thead><tbody>{rows}</tbody></table></div>")
            continue
        if line.startswith("#"):
            level = len(line) - len(line.lstrip("#"))
            out.append(f"<h{level}>{_inline(line[level:].strip())}</h{level}>")
        elif line.startswith("- "):
            items = []
            while i < len(lines) and lines[i].startswith("- "):
                items.append(f"<li>{_inline(lines[i][2:])}</li>")
                i += 1
            out.append("<ul>" + "".join(items) + "</ul>")
            continue
        elif line.strip():
            out.append(f"<p>{_inline(line)}</p>")
        i += 1
    return "\n".join(out)


def _data_uri(path):
    kind = {".png": "image/png", ".gif": "image/gif"}[Path(path).suffix]
    return f"data:{kind};base64,{base64.b64encode(Path(path).read_bytes()).decode()}"


def _figure(path, caption):
    return (f'<figure><img src="{_data_uri(path)}" alt="{html.escape(caption)}">'
            f"<figcaption>{html.escape(caption)}</figcaption></figure>")


def write_page(out_dir):
    """Write ``out_dir/index.html`` from the board's scoreboard.md, pictures and S2 animations; return its path."""
    out_dir = Path(out_dir)
    board = (out_dir / "scoreboard.md").read_text()
    title, _, rest = board.partition("\n")
    parts = [f"<h1>{_inline(title.lstrip('# '))}</h1>"]
    if (out_dir / "summary.png").exists():
        parts.append(_figure(out_dir / "summary.png", "Each scenario's ranking figure: the worst case, or on the "
                                                      "paired design the median with its 95 % interval as an error "
                                                      "bar and the 90th percentile as a marker."))
    parts.append(markdown_to_html(rest))
    runs = [(out_dir / f"{s}.png", f"{s}: every controller's nominal run") for s in ("S1", "S2", "S7")]
    if any(path.exists() for path, _ in runs):
        parts.append("<h2>Runs</h2>" + "".join(_figure(path, caption) for path, caption in runs if path.exists()))
    gifs = sorted((out_dir / "animations").glob("S2_*.gif"))
    if gifs:
        parts.append('<h2>S2, animated</h2><div class="animations">'
                     + "".join(_figure(gif, gif.stem.replace("_", ", ", 1)) for gif in gifs) + "</div>")
    page = (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_inline(title.lstrip("# "))}'
            f"</title><style>{STYLE}</style></head><body>\n" + "\n".join(parts) + "\n</body></html>\n")
    path = out_dir / "index.html"
    partial = path.with_name(".index.html.partial")
    partial.write_text(page)
    partial.replace(path)
    return path
