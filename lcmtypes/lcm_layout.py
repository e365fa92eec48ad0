#!/usr/bin/env python3
"""Writes lcm_layout.hpp: the wire layout of every LCM type in lcmtypes/, for the one check that
every string and array length of a payload fits before lcm-gen's decoder reads it
(formats/lcm_layout_check.hpp).

lcm-gen's C++ decoders check a string's length against the payload's end but not its sign, and
take an array's dimension from the payload unchecked: a length of INT_MIN overflows, one of -1
reaches std::string::assign or std::vector::resize as a huge size. Generated from the same .lcm
files as the decoders, so a type or field added later is covered without anyone remembering to.

Usage: lcm_layout.py OUT.hpp TYPE.lcm...
The subset of the LCM type language used here (and by bot_core's types): primitive fields,
strings, nested structs (same package or package-qualified), fixed or member-sized dimensions.
Anything else is refused with the file and line, so that the generator never guesses.
"""
import re
import sys

PRIMITIVES = {"int8_t": 1, "int16_t": 2, "int32_t": 4, "int64_t": 8, "float": 4, "double": 8, "byte": 1,
              "boolean": 1}
INTEGERS = {"int8_t", "int16_t", "int32_t", "int64_t"}  # what may size an array
MAX_FIELDS = 48
PREAMBLE = f"""enum class Kind : std::uint8_t {{ Primitive, String, Struct }};
// A dimension: a number, or (member >= 0) the value of an earlier integer member of the struct.
struct Dim {{
  std::int64_t fixed;
  int member;
}};
struct Field {{
  const char* name;
  Kind kind;
  int size;      // Primitive: bytes of one element
  bool integer;  // Primitive: an integer (may size a later array)
  int nested;    // Struct: index into kTypes
  int ndims;
  std::array<Dim, 4> dims;
}};
struct Type {{
  const char* name;  // package.struct
  int nfields;
  std::array<Field, {MAX_FIELDS}> fields;
}};

"""
FIELD = re.compile(r"^([A-Za-z_][A-Za-z0-9_.]*)\s+([A-Za-z_][A-Za-z0-9_]*)\s*((?:\[\s*[A-Za-z0-9_]+\s*\]\s*)*)$")


def fail(path, line, why):
    sys.exit(f"{path}:{line}: {why}")


def parse(path):
    """(package, struct, [(type, name, [dim...], line)]) of one .lcm file."""
    text = open(path).read()
    lines = [re.sub(r"//.*", "", l) for l in text.split("\n")]
    text = "\n".join(lines)
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    package = re.search(r"\bpackage\s+([A-Za-z_][A-Za-z0-9_.]*)\s*;", text)
    struct = re.search(r"\bstruct\s+([A-Za-z_][A-Za-z0-9_]*)\s*\{(.*)\}", text, flags=re.S)
    if not package or not struct:
        fail(path, 1, "expected 'package NAME;' and one 'struct NAME { ... }'")
    body_line = text[:struct.start(2)].count("\n") + 1
    fields = []
    for offset, statement in statements(struct.group(2)):
        line = body_line + offset
        if statement.startswith("const "):
            continue
        m = FIELD.match(statement)
        if not m:
            fail(path, line, f"cannot read field '{statement}'")
        dims = re.findall(r"\[\s*([A-Za-z0-9_]+)\s*\]", m.group(3))
        fields.append((m.group(1), m.group(2), dims, line))
    return package.group(1), struct.group(1), fields


def statements(body):
    """(line offset, text) of each ';'-terminated statement of a struct body."""
    pos = 0
    for part in body.split(";")[:-1]:
        start = pos + len(part) - len(part.lstrip())
        yield body[:start].count("\n"), " ".join(part.split())
        pos += len(part) + 1


def main():
    out, sources = sys.argv[1], sys.argv[2:]
    types = {}
    for path in sources:
        package, name, fields = parse(path)
        types[f"{package}.{name}"] = (package, name, fields, path)
    order = sorted(types)
    index = {full: i for i, full in enumerate(order)}
    rows = []
    for full in order:
        package, name, fields, path = types[full]
        members = [f[1] for f in fields]
        entries = []
        for i, (ftype, fname, dims, line) in enumerate(fields):
            dim_specs = []
            for d in dims:
                if d.isdigit():
                    dim_specs.append(f"{{{int(d)}, -1}}")
                elif d in members[:i] and fields[members.index(d)][0] in INTEGERS and not fields[members.index(d)][2]:
                    dim_specs.append(f"{{0, {members.index(d)}}}")
                else:
                    fail(path, line, f"dimension '{d}' of '{fname}' is neither a number nor an earlier integer member")
            if len(fields) > MAX_FIELDS:
                fail(path, line, f"more than {MAX_FIELDS} fields (raise MAX_FIELDS in lcm_layout.py)")
            if len(dim_specs) > 4:
                fail(path, line, f"'{fname}' has more than four dimensions")
            dims_text = "{{" + ", ".join(dim_specs) + "}}" if dim_specs else "{}"
            if ftype in PRIMITIVES:
                kind, size, sub = "Kind::Primitive", PRIMITIVES[ftype], -1
                integer = "true" if ftype in INTEGERS else "false"
            elif ftype == "string":
                kind, size, sub, integer = "Kind::String", 0, -1, "false"
            else:
                nested = ftype if "." in ftype else f"{package}.{ftype}"
                if nested not in index:
                    fail(path, line, f"type '{ftype}' of '{fname}' is not among the generated types")
                kind, size, sub, integer = "Kind::Struct", 0, index[nested], "false"
            entries.append(f'      {{"{fname}", {kind}, {size}, {integer}, {sub}, {len(dim_specs)}, {dims_text}}},')
        rows.append((full, package, name, entries))
    with open(out, "w") as f:
        f.write("// Generated by lcmtypes/lcm_layout.py from lcmtypes/*.lcm: do not edit.\n")
        f.write("// The wire layout of every type (formats/lcm_layout_check.hpp reads it).\n#pragma once\n\n")
        f.write("#include <array>\n#include <cstdint>\n#include <tuple>\n\n")
        for full, package, name, _ in rows:
            f.write(f"#include <{package.replace('.', '/')}/{name}.hpp>\n")
        f.write("\nnamespace rsd::formats::lcm_layout {\n\n")
        f.write(PREAMBLE)
        f.write(f"inline constexpr std::array<Type, {len(rows)}> kTypes{{{{\n")
        for full, package, name, entries in rows:
            f.write(f'  Type{{"{full}", {len(entries)}, {{{{\n' + "\n".join(entries) + "\n  }}},\n")
        f.write("}};\n\n")
        f.write("// Every generated C++ type, in kTypes' order.\n")
        f.write("using AllMessages = std::tuple<" + ", ".join(f"{p.replace('.', '::')}::{n}" for _, p, n, _ in rows) + ">;\n\n")
        f.write("template <class Msg>\ninline constexpr int kIndex = -1;\n")
        for full, package, name, _ in rows:
            f.write(f"template <>\ninline constexpr int kIndex<{package.replace('.', '::')}::{name}> = {index[full]};\n")
        f.write("\n}  // namespace rsd::formats::lcm_layout\n")


main()
