"""Test suite configuration.

Tests under tests/unit need neither LIGGGHTS nor MPI; tests under
tests/engine start LIGGGHTS through vibrofeed and take seconds each.
Shared helpers live in tests/helpers.py.
"""
