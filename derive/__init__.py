"""The symbolic derivation of the model (SymPy) and the writer of generated/ (CasADi C)."""
