"""theoria: a laboratory of Euler's rotational celestial mechanics."""
