"""The LaTeX model report: figures (matplotlib) and the report context."""
