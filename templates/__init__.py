"""Jinja2 templates of wirecal's outputs (controller programs, reports); package data only."""
