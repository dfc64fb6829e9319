"""Example robot files, plans and validation setups (package data: the demo uses them)."""
