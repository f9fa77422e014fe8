"""The comparison report: its tables, warnings, parameters and tension, rendered once as
Markdown and once as self-contained HTML."""
