"""Public programs of each controller language the checkers run on (see SOURCES.toml)."""
