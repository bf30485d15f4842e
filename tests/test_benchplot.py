"""The bench's figure (cablecheck.bench.plot) from small tables made here with the
bench's own columns: a PNG is written where asked, rows the side-by-side
panel leaves out (no other time, fcl query only, detection) do no harm.
The figure of a real (tiny) bench run is checked in test_bench."""

from __future__ import annotations

from cablecheck.bench.plot import plot
from cablecheck.bench.table import Table


def _tables() -> dict[str, Table]:
    disc = Table("discretisation", "d", ["config", "spacing_r", "ms_per_check", "ms_large", "pairs", "ref_pairs",
                                         "ref_hard", "missed_hard", "missed", "false_alarms", "worst_error_mm"])
    disc.add("points 2r", 2.0, 1.0, 3.0, 10, 10, 2, 0, 0, 0, 0.4)
    disc.add("exact", None, 2.0, 6.0, 10, 10, 2, 0, 0, 0, 0.0)
    phys = Table("physics", "p", ["reference", "elements", "elements_per_m", "timestep_ms", "error_pct",
                                  "ms_per_sim_s", "warnings"])
    for ref in ("catenary", "cantilever"):
        for n, err in ((10, 2.0), (20, 0.5)):
            phys.add(ref, n, n / 1.0, 1.0, -err, 10.0 * n, "")
    scale = Table("scale", "s", ["axis", "cables", "points", "parts", "ms_points", "ms_exact",
                                 "us_per_point_points", "us_per_point_exact"])
    for k in (1, 2, 4):
        scale.add("cables", 10 * k, 2000 * k, 30, 1.0 * k, 2.0 * k, 0.5, 1.0)
        scale.add("parts", 10, 2000, 30 * k, 1.0 * k, 2.0 * k, 0.5, 1.0)
    side = Table("side_by_side", "b", ["scene", "method", "points", "parts", "checker_ms", "other", "other_ms",
                                       "ratio"])
    side.add("random", "exact", 2000, 30, 1.5, "fcl distance", 15.0, 10.0)
    side.add("random", "points", 2000, 30, 1.0, "fcl query only", 5.0, 5.0)
    side.add("drawer", "points", 400, 8, 0.2, "detect mj_collision", 0.1, 0.5)
    side.add("arm", "points", 400, 8, 0.2, "mj_collision", None, None)
    return {"discretisation": disc, "physics": phys, "scale": scale, "side_by_side": side}


def test_the_figure_is_a_png_where_asked(tmp_path):
    path = plot(_tables(), tmp_path / "bench.png")
    assert path == tmp_path / "bench.png"
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bench.png"]
