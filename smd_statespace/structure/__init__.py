"""A crowd of SMD people on a structure's modes (issue 48)."""
