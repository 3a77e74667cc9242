"""Streamed evaluation of trajectory files of any length in bounded memory (``gsfric simulate``)."""
