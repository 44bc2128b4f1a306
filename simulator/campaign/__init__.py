"""Monte Carlo campaigns: many seeded runs of one world on local worker processes or a Ray cluster, resumable,
aggregated."""
