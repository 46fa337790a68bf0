"""`crane-fmu build` makes again only what changed (content hashes of what each file is made from).

- A second build of the same sources makes nothing and leaves every file as it was.
- A changed source makes its outputs again; `--force` makes every one again.
- An output deleted or altered since it was made is made again (the record's rule, on plain files).
- `build --component MODULE.py --out DIR` writes everything under DIR (FMI 3.0 in DIR/fmi3).
"""

from pathlib import Path

import pd_controller

from crane_fmu import systems
from crane_fmu.build_scripts import incremental
from crane_fmu.cli import main


def _build(capsys, *argv):
    assert main(["build", *argv]) == 0
    lines = capsys.readouterr().out.splitlines()
    return lines[:-1], lines[-1]  # the files made, the summary


def test_a_second_full_build_makes_nothing(fmu_dir, capsys):
    """The session's build (every registered component, the benchmark's too), built again as a user would."""
    files = {p: (p.stat().st_mtime_ns, incremental.file_digest(p)) for p in fmu_dir.parent.rglob("*.fmu")}
    assert len(files) >= 60
    made, summary = _build(capsys, "--out", str(fmu_dir), "--bench")
    assert made == [] and summary.startswith("0 made, ") and " up to date in " in summary, summary
    assert {p: (p.stat().st_mtime_ns, incremental.file_digest(p)) for p in fmu_dir.parent.rglob("*.fmu")} == files


def test_a_component_build_makes_again_only_what_changed(tmp_path, capsys):
    module = tmp_path / "src" / "pd_mine.py"
    module.parent.mkdir()
    module.write_text(Path(pd_controller.__file__).read_text().replace('"PdController"', '"PdMine"'))
    out = tmp_path / "build" / "mine"
    argv = ["--component", str(module), "--out", str(out)]
    made, summary = _build(capsys, *argv)
    fmus = [out / "PdMine.fmu", out / "fmi3" / "PdMine.fmu"]
    assert sorted(made) == sorted(map(str, fmus)) and summary == f"2 made, 0 up to date in {out}"
    assert sorted(p.name for p in (tmp_path / "build").iterdir()) == ["mine"]  # nothing beside DIR
    assert _build(capsys, *argv)[0] == []  # nothing changed
    module.write_text(module.read_text().replace("PD law on the trolley position", "PD law, edited"))
    assert sorted(_build(capsys, *argv)[0]) == sorted(map(str, fmus))  # a changed source
    made, summary = _build(capsys, *argv, "--force")
    assert sorted(made) == sorted(map(str, fmus)) and summary == f"2 made, 0 up to date in {out}"


def test_the_record_keeps_an_output_only_for_the_same_key(tmp_path):
    """The rule behind the build, on plain files: same key and same file -> kept; else made again."""
    target = tmp_path / "out.txt"
    made = []

    def produce(text):
        made.append(text)
        target.write_text(text)
        return target

    for key, text, expect in [("a", "1", ["1"]), ("a", "2", []), ("b", "3", ["3"])]:
        made.clear()
        with incremental.building(tmp_path) as record:
            record.make(target, key, lambda text=text: produce(text))
        assert made == expect, key
    target.write_text("changed by hand")
    with incremental.building(tmp_path) as record:
        record.make(target, "b", lambda: produce("4"))
    assert target.read_text() == "4"
    with incremental.building(tmp_path, force=True) as record:
        record.make(target, "b", lambda: produce("5"))
    assert target.read_text() == "5" and record.made == [target] and record.kept == []


def test_an_edit_of_the_closed_loops_interface_makes_the_one_fmus_and_containers_again(tmp_path, monkeypatch):
    """closed_loop.py chooses what a one-FMU and a container expose: both keys read it."""
    system = systems.get("lqr")
    copy = tmp_path / "closed_loop.py"
    copy.write_text(incremental.CLOSED_LOOP.read_text())
    monkeypatch.setattr(incremental, "CLOSED_LOOP", copy)

    def keys():
        return (incremental.one_fmu_key(system, sorted(set(system.instances.values())), 2, {}, []),
                incremental.container_key(system, []))

    before = keys()
    copy.write_text(copy.read_text() + "\n# edited\n")
    assert all(a != b for a, b in zip(before, keys()))
