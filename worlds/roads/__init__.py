"""Road networks: directed roads with smooth arc-length centre-lines (``road``, built by ``spline``), their graph
(``network``) and surface footprints / meshes for rendering and placement checks (``mesh``)."""
