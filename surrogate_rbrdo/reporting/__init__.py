"""Tables and figures (matplotlib, Agg backend) written into a run folder."""
