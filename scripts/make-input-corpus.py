#!/usr/bin/env python3
"""Writes the bad-input and good-input corpora under tests/ (R1-TEST-020).

Each bad case is a file plus a row in tests/bad_input/cases.tsv: FILE, COMMAND (info or convert),
and a fragment the one-line error must contain. Run from the repository root; the files are
committed, so this only needs to run again when cases are added.
"""
import os
import struct

BAD = "tests/bad_input"
GOOD = "tests/good_input"
cases = []


def put(folder, name, data):
    path = os.path.join(folder, name)
    with open(path, "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode("utf-8"))
    return name


def bad(name, data, expect, command="info"):
    cases.append((put(BAD, name, data), command, expect))


def pid(i):
    return bytes([i]) * 32


def record(frm=1, to=2, token=0, amount=1 << 32, valence=1, height=1, neuron=0, pad=b"\0\0\0"):
    return (pid(neuron) + pid(frm) + pid(to) + struct.pack("<I", token) +
            amount.to_bytes(16, "little") + struct.pack("<b", valence) + struct.pack("<Q", height) + pad)


CONFIG = ('chain_id = "test"\nblock = 10\ncaptured_at = 0\nformat_version = 1\n\n[tokens]\n'
          '0 = { symbol = "boot", weight = 1000 }\n')


def graph(records, config=CONFIG, front_extra="", size=None, files=None, sections=None, trailer=b""):
    body = b"".join(records)
    if files is None:
        files = [("card", "md", None), ("config", "toml", None),
                 ("cyberlinks", "records", len(body) if size is None else size)]
    front = '[cyb]\ntypes = ["graph"]\nname = "t"\n' + front_extra
    for name, fmt, sz in files:
        front += '\n[[files]]\nname = "%s"\nformat = "%s"\n' % (name, fmt)
        if sz is not None:
            front += "size = %s\n" % sz
    if sections is None:
        sections = [("card", b"# t\n"), ("config", config.encode()), ("cyberlinks", body)]
    out = front.encode()
    for name, data in sections:
        out += b"~~~" + name.encode() + b"\n" + data
    return out + trailer


os.makedirs(BAD, exist_ok=True)
os.makedirs(GOOD, exist_ok=True)

# Edge lists.
bad("empty.tsv", "", "empty file")
bad("only_comments.tsv", "# nothing here\n\n   \n", "no links")
bad("only_self_loops.tsv", "a\ta\nb\tb\t2\n", "no links besides 2 self-loops")
bad("bad_utf8.tsv", b"a\tb\nc\xff\td\n", ":2: particle name is not valid UTF-8")
bad("overlong_utf8.tsv", b"\xc0\xafx\ty\n", ":1: particle name is not valid UTF-8")
bad("nan_weight.tsv", "a\tb\tnan\n", ":1: weight 'nan' is not a finite number")
bad("inf_weight.tsv", "a\tb\t1\nb\tc\t-Infinity\n", ":2: weight '-Infinity' is not a finite number")
bad("negative_weight.tsv", "a\tb\t-0.5\n", "is negative")
bad("zero_weight.tsv", "a\tb\t0.000\n", "weight is zero")
bad("huge_weight.tsv", "a\tb\t1e40\n", "weight is too large")
bad("tiny_weight.tsv", "a\tb\t1e-20\n", "rounds to zero")
bad("hex_weight.tsv", "a\tb\t0x10\n", "is not a number")
bad("bad_valence.tsv", "a\tb\t1\t2\n", "valence '2' is not -1, 0 or +1")
bad("too_many_fields.tsv", "a\tb\t1\t1\textra\n", "expected 2 to 4 tab-separated fields")
bad("one_field.tsv", "from\tto\nlonely\n", ":2: expected 2 to 4 tab-separated fields")
bad("empty_name.tsv", "\tb\n", "empty source name")
bad("nul_name.tsv", b"a\0b\tc\n", "NUL byte in a particle name")
bad("crlf_then_bad.tsv", "a\tb\r\nc\td\r\ne\tf\tnope\r\n", ":3: weight 'nope' is not a number")
bad("unterminated_quote.csv", 'a,b\n"c,d\n', ":2: unterminated quoted field")
bad("text_after_quote.csv", '"a"x,b\n', "text after a closing quote")
bad("quote_in_field.csv", 'a"b,c\n', "quote inside an unquoted field")
bad("lone_cr.csv", "a,b\rc,d\n", "carriage return")
bad("csv_fields.csv", "a,b,1,0,9\n", "expected 2 to 4 comma-separated fields")
# Matrix Market.
bad("no_banner.mtx", "3 3 1\n1 2 1\n", ":1: expected a '%%MatrixMarket' banner")
bad("array.mtx", "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n", "format 'array' is not supported")
bad("complex.mtx", "%%MatrixMarket matrix coordinate complex general\n2 2 1\n1 2 1 0\n", "field 'complex' is not supported")
bad("skew.mtx", "%%MatrixMarket matrix coordinate real skew-symmetric\n2 2 1\n2 1 1\n", "symmetry 'skew-symmetric'")
bad("rectangular.mtx", "%%MatrixMarket matrix coordinate real general\n2 3 1\n1 2 1\n", "not square")
bad("truncated.mtx", "%%MatrixMarket matrix coordinate real general\n3 3 3\n1 2 1\n2 3 1\n", "truncated file")
bad("extra.mtx", "%%MatrixMarket matrix coordinate pattern general\n3 3 1\n1 2\n2 3\n", ":4: more entries than")
bad("index_range.mtx", "%%MatrixMarket matrix coordinate real general\n3 3 1\n1 4 1\n", ":3: index out of range")
bad("negative.mtx", "%%MatrixMarket matrix coordinate real symmetric\n3 3 1\n2 1 -1.5\n", "is negative")
bad("no_size.mtx", "%%MatrixMarket matrix coordinate real general\n% only a comment\n", "no size line")
# .graph files.
good_records = [record(1, 2), record(2, 3, valence=-1, height=2), record(3, 1, amount=5 << 32, height=2)]
bad("truncated.graph", graph(good_records)[:-40], "remain (truncated file?)")
bad("size_not_multiple.graph", graph([b"x" * 100], size=100), "is not a multiple of 128")
bad("front_matter_ub.graph", graph(good_records, front_extra="[&\n"), "narrow TOML subset")
bad("front_matter_float.graph", graph(good_records, front_extra="x = 1.5\n"), "only decimal integers")
bad("multiline_string.graph", graph(good_records, front_extra='x = """a\n'), "multi-line strings")
bad("no_chain_id.graph", graph(good_records, config=CONFIG.replace('chain_id = "test"\n', "")), "needs a string chain_id")
bad("config_version.graph", graph(good_records, config=CONFIG.replace("format_version = 1", "format_version = 2")),
    "format_version 2 is not supported")
bad("no_tokens.graph", graph(good_records, config=CONFIG.split("[tokens]")[0]), "needs a [tokens] table")
bad("negative_token_weight.graph", graph(good_records, config=CONFIG.replace("weight = 1000", "weight = -5")),
    "negative weight")
bad("dup_files.graph", graph(good_records, files=[("card", "md", None), ("card", "md", None), ("config", "toml", None),
                                                  ("cyberlinks", "records", 384)]), "duplicate file name 'card'")
bad("section_order.graph", graph(good_records, sections=[("config", CONFIG.encode()), ("card", b"# t\n"),
                                                         ("cyberlinks", b"".join(good_records))]),
    "section 'config' found where [[files]] lists 'card'")
bad("missing_section.graph", graph(good_records, files=[("card", "md", None), ("config", "toml", None)],
                                   sections=[("card", b"# t\n"), ("config", CONFIG.encode())]),
    "required section 'cyberlinks' is missing")
bad("unlisted_section.graph", graph(good_records, sections=[("card", b"# t\n"), ("config", CONFIG.encode()),
                                                            ("cyberlinks", b"".join(good_records)), ("extra", b"x\n")]),
    "section 'extra' has no [[files]] entry")
bad("bad_valence.graph", graph([record(valence=5)]), "valence 5 is not -1, 0 or +1")
bad("padding.graph", graph([record(pad=b"\0\1\0")]), "padding bytes are not zero")
bad("unknown_token.graph", graph([record(token=3)]), "token 3 is not in the config")
bad("height_order.graph", graph([record(height=5), record(height=4)]), "records must be in chain order")
bad("height_range.graph", graph([record(height=11)]), "is outside [1, 10]")
bad("height_zero.graph", graph([record(height=0)]), "is outside [1, 10]")
bad("trailing_bytes.graph", graph(good_records, trailer=b"junk"), "unexpected bytes after binary section")
bad("huge_size.graph", graph(good_records, size=10**18), "declares 1000000000000000000 bytes")
bad("negative_size.graph", graph(good_records, size=-128), "'size' must be a non-negative integer")
bad("not_a_graph.graph", "just some text\nwith lines\n", "not a .graph file")
bad("no_front_matter.graph", b"~~~card\n# x\n", "front matter is missing")
bad("binary_config.graph", graph(good_records, files=[("card", "md", None), ("config", "toml", len(CONFIG)),
                                                      ("cyberlinks", "records", 384)]), "section 'config' must be text")
bad("weight_overflow.graph", graph([record(amount=(1 << 128) - 1)]), "reaches 2^127")
bad("only_self_loops.graph", graph([record(1, 1), record(2, 2)]), "no links besides 2 self-loops")
bad("no_links.graph", graph([]), "no links")
bad("titles_unknown_id.graph",
    graph(good_records, files=[("card", "md", None), ("config", "toml", None), ("titles", "tsv", None),
                               ("cyberlinks", "records", 384)],
          sections=[("card", b"# t\n"), ("config", CONFIG.encode()), ("titles", ("09" * 32 + "\tNine\n").encode()),
                    ("cyberlinks", b"".join(good_records))]), "is not in the snapshot")
bad("crystal_bad_type.graph",
    graph(good_records, files=[("card", "md", None), ("config", "toml", None), ("crystal", "tsv", None),
                               ("cyberlinks", "records", 384)],
          sections=[("card", b"# t\n"), ("config", CONFIG.encode()),
                    ("crystal", ("01" * 32 + "\twidget\tmath\tatom\n").encode()),
                    ("cyberlinks", b"".join(good_records))]), "unknown crystal type 'widget'")
bad("convert_truncated.graph", graph(good_records)[:-1], "truncated", command="convert")
bad("convert_bad.tsv", "a\tb\t-1\n", "is negative", command="convert")

with open(os.path.join(BAD, "cases.tsv"), "w") as f:
    f.write("# file\tcommand\texpected fragment of the one-line error (written by scripts/make-input-corpus.py)\n")
    for name, command, expect in cases:
        f.write("%s\t%s\t%s\n" % (name, command, expect))

# Good inputs with known contents (tests/good_input): CRLF, BOM, header rows, quoting, comments.
put(GOOD, "crlf_bom_header.tsv", b"\xef\xbb\xbffrom\tto\tweight\tvalence\r\n# a comment\r\nalpha beta\tgamma\t2.5\t1\r\n"
    b"gamma\tdelta\t0.125\t-1\r\n\r\ndelta\talpha beta\r\nalpha beta\talpha beta\t3\r\n")
put(GOOD, "quoted.csv", 'from,to,weight\n"a, the first",b,1\n"say ""hi""","multi\nline",2\n# comment\nb,"#hash",0.5\n')
put(GOOD, "symmetric.mtx", "%%MatrixMarket matrix coordinate real symmetric\n% comment\n4 4 5\n1 1 9\n2 1 1.5\n3 2 0\n"
    "4 3 2\n3 1 1\n")
put(GOOD, "extension_section.graph", graph(good_records,
    files=[("card", "md", None), ("config", "toml", None), ("notes", "md", None), ("cyberlinks", "records", 384),
           ("blob", "bin", 3)],
    sections=[("card", b"# t\r\n"), ("config", CONFIG.encode()), ("notes", b"kept as is\n"),
              ("cyberlinks", b"".join(good_records) + b"\n"), ("blob", b"\x00\x01\x02")]))
print("%d bad cases" % len(cases))
