"""Subcommands of docs/DESIGN.md that are not built yet: none are left (every command is built)."""
