"""The numeric modules `python -m derive` renders (numpy only; do not edit: regenerate)."""
