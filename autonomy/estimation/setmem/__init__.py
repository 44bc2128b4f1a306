"""Set-membership (bounded-error) search and tracking estimator on unions of polygons."""
