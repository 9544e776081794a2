"""Configuration: the profile schema, quantities with units, YAML loading and the input limits.

- :mod:`.schema`: typed dataclass fields with bounds and units, and building a section from YAML data.
- :mod:`.units`: quantities given with a unit (``"20 mm"``) turned into SI.
- :mod:`.yamlload`: YAML with duplicate keys refused and its size, depth and aliases bounded.
- :mod:`.input_limits`: each bound on a number given on the command line or in a file, and why.

The package imports nothing at import: each module is imported on its own.
"""
