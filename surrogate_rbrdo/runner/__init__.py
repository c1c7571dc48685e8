"""Configs -> objects, run folders, and the ``rbrdo`` command line."""
