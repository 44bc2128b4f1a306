"""Team protocols: the ways a team of UAVs shares information, each one class with one ``step`` over its members.

See :mod:`autonomy.team.base` for the interface and the context the simulator hands in.
"""
