"""File input and output, one wrapper each, used by every file kind of ur3hanoi.

- :mod:`~ur3hanoi.io.limits`: the caps on input files (size, nesting, nodes, aliases, number length).
- :mod:`~ur3hanoi.io.reading`: read an input file's bytes safely (regular files only, never blocks, size cap).
- :mod:`~ur3hanoi.io.yaml_loader`: the one strict YAML loader (UTF-8 only, duplicate keys and bombs refused).
- :mod:`~ur3hanoi.io.number`: a number's valid range (the schemas' and the command-line options').
- :mod:`~ur3hanoi.io.schema`: declarative schemas and the one validator (unknown keys with suggestions, types,
  ranges, NaN/inf).
- :mod:`~ur3hanoi.io.atomic`: the one writer (output path checks, atomic replace, a lock for read-modify-write).
"""
