"""Stream schemas (simulator.streams): the recorder checks each declared stream's first row against its schema."""

import numpy as np
import pytest

from simulator.record import RunRecorder
from simulator.streams import STREAMS


def test_a_row_with_the_declared_columns_is_written_and_one_without_them_is_refused(tmp_path):
    rec = RunRecorder(tmp_path, schemas=STREAMS)
    cols = STREAMS["measurement_sharing"].columns
    rec.append("measurement_sharing", **dict.fromkeys(cols, 1))
    with pytest.raises(KeyError, match="commands"):
        rec.append("commands", tick=1, t=0.0, uav=0)  # columns missing
    reordered = dict.fromkeys(reversed(STREAMS["routing"].columns), 0)
    with pytest.raises(KeyError, match="routing"):
        rec.append("routing", **reordered)
    rec.append("an_undeclared_stream", x=1.0)  # streams of other writers are not checked
    rec.close()


def test_blank_rows_are_nan_but_the_values_given_in_the_declared_order():
    row = STREAMS["commands"].blank(tick=3, t=0.25, uav=1, kind="VelocitySetpoint", vx=2.0)
    assert tuple(row) == STREAMS["commands"].columns
    assert row["vx"] == 2.0 and row["kind"] == "VelocitySetpoint" and np.isnan(row["speed"])
    with pytest.raises(KeyError, match="bogus"):
        STREAMS["commands"].blank(bogus=1)
