"""Which source made a result: fingerprints, the runs' recorded code, and what a reproduction report says of it."""

from __future__ import annotations

import json
from collections import Counter

from simulator.provenance import code_versions, fingerprint, source_fingerprint, versions_text
from simulator.reproduce.report import PaperReport, paper_markdown, verdicts_record


def _tree(root, files):
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return [root / rel for rel in files if rel.endswith(".py")]


def test_a_fingerprint_changes_with_any_byte_name_or_world_file_and_nothing_else(tmp_path):
    base = {"pkg/a.py": "x = 1\n", "pkg/b.py": "y = 2\n", "worlds/w.yaml": "name: w\n"}
    fps = {}
    for label, change in (("same", {}), ("again", {}), ("byte", {"pkg/a.py": "x = 2\n"}),
                          ("world", {"worlds/w.yaml": "name: v\n"}), ("new world", {"worlds/v.yaml": "name: v\n"})):
        root = tmp_path / label.replace(" ", "_")
        fps[label] = fingerprint(_tree(root, {**base, **change}), root=root)
    renamed = tmp_path / "renamed"
    fps["renamed"] = fingerprint(_tree(renamed, {"pkg/c.py": "x = 1\n", "pkg/b.py": "y = 2\n",
                                                 "worlds/w.yaml": "name: w\n"}), root=renamed)
    assert fps["same"] == fps["again"]  # the location of the tree does not enter it
    assert len({fps[k] for k in ("same", "byte", "world", "new world", "renamed")}) == 5
    assert len(source_fingerprint()) == 16 and source_fingerprint() == source_fingerprint()


def test_runs_are_counted_by_the_source_that_made_them_and_unreadable_records_are_not_trusted(tmp_path):
    contents = {"r0": {"code": "aaaa"}, "r1": {"code": "aaaa"}, "r2": {"code": "bbbb"}, "r3": {"seed": 1},
                "r4": "not json {", "r5": ["code"], "r6": {"code": 7}}
    dirs = []
    for name, body in contents.items():
        d = tmp_path / name
        d.mkdir()
        (d / "run.json").write_text(body if isinstance(body, str) else json.dumps(body))
        dirs.append(d)
    dirs.append(tmp_path / "missing")
    counts = code_versions(dirs)
    assert counts == Counter({"aaaa": 2, "bbbb": 1, "unrecorded": 5})
    assert versions_text(Counter({"aaaa": 3}), current="aaaa") == "all 3 physics runs by this source (code aaaa)"
    text = versions_text(counts, current="aaaa")
    assert text == ("of 8 physics runs, 2 by this source (code aaaa), 5 made before runs recorded their code, "
                    "1 by code bbbb")
    assert versions_text(Counter({"bbbb": 2}), current="aaaa") == "of 2 physics runs, 2 by code bbbb"
    assert versions_text(Counter(), current="aaaa") == ""


def test_a_report_says_when_its_physics_runs_came_from_more_than_one_source():
    rep = PaperReport(paper="003", title="t", runs=2, setup="s")
    one = paper_markdown(PaperReport(paper="003", title="t", runs=2, setup="s",
                                     codes={source_fingerprint(): 4}), "cmd")
    assert f"Provenance: all 4 physics runs by this source (code {source_fingerprint()})." in one
    mixed = PaperReport(paper="003", title="t", runs=2, setup="s", codes={source_fingerprint(): 3, "0123": 1})
    text = paper_markdown(mixed, "cmd")
    assert "**Provenance: of 4 physics runs, 3 by this source" in text and "1 by code 0123**" in text
    assert "Provenance" not in paper_markdown(rep, "cmd")  # no physics runs, nothing said
    other = paper_markdown(PaperReport(paper="003", title="t", runs=2, setup="s", codes={"0123": 2}), "cmd")
    assert "**Provenance: of 2 physics runs, 2 by code 0123**" in other  # all by another source: flagged too
    assert verdicts_record(mixed, "cmd")["physics_runs_by_code"] == {"0123": 1, source_fingerprint(): 3}
