"""Data files shipped with theoria (installed as the package data of `theoria.assets`)."""
