"""Figures (PNG, matplotlib) and tables (terminal, Markdown) of the reports."""
