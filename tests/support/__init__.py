"""Shared test helpers (importable: ``tests/`` is on pytest's ``pythonpath``)."""
