"""The SymPy side: stand descriptions derived into H, q, the remount formulas and the norm relation."""
