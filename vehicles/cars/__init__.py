"""Parameter files of the shipped car types, one module per type (``sedan``, ``van``), each defining ``PARAMS``."""
