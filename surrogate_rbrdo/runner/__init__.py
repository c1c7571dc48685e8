"""Config schema and parsing, run folders, the ``rbrdo`` command line and the experiment kinds
(thin compositions of library calls; ``docs/runner.md``)."""
