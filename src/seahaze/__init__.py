"""seahaze: physically based maritime haze datasets with exact visibility labels."""

__version__ = "0.1.0"
