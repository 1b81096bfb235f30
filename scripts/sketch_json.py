"""Reading sketch files from the scripts: the sketch format allows // comments, JSON does not."""
import json


def strip_comments(text):
    """The text with every // comment outside a string removed (plain JSON)."""
    out, i, in_string = [], 0, False
    while i < len(text):
        c = text[i]
        if in_string:
            out.append(c)
            if c == "\\":
                out.append(text[i + 1])
                i += 1
            elif c == '"':
                in_string = False
        elif c == '"':
            in_string = True
            out.append(c)
        elif text.startswith("//", i):
            while i < len(text) and text[i] != "\n":
                i += 1
            continue
        else:
            out.append(c)
        i += 1
    return "".join(out)


def read_sketch(path):
    """The sketch file at `path` as a dict."""
    with open(path) as f:
        return json.loads(strip_comments(f.read()))
