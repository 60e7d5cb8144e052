"""Bundled example specifications (package data)."""
