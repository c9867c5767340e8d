"""What every model family shares and none owns: the NumPy/JAX array switch, the JSON
sanitiser, lazy imports, the Numba cache, optional extras."""
