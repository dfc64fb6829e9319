"""wirecal.gen — rendering of wirecal's text outputs from the Jinja2 templates in
``wirecal.templates`` (controller programs, reports)."""
