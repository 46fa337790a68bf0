"""The board's statistics and pictures, each scenario's begun as soon as its last row is in.

``crane-fmu compare`` gives each row to :meth:`BoardDrawer.add` as its case finishes (or from the journal): when a
scenario has all its rows, its statistics (paired scenarios), its picture (:data:`~.score_plots.RUN_PICTURES`) and
its animations go to a pool of processes, while the other scenarios' cases still run. The summary, which needs every
row, is drawn at the end. Each is made from its scenario's rows in the board's order, so its figures and bytes are
those of drawing them all at the end (tested).
"""

from collections import Counter
from pathlib import Path

from . import ranking, score_plots
from .scenarios import paired


def first_scenarios(animate):
    """The order in which a board's scenarios are best run: the animated ones first (their drawing takes longest),
    then those with a picture, then the paired ones (their statistics), then the rest."""
    return [*animate, *score_plots.RUN_PICTURES, *paired()]


class BoardDrawer:
    """Begins each scenario's statistics, picture and animations in ``pool`` when its last row is in.

    Parameters
    ----------
    pool : concurrent.futures.Executor
    order : list of (case_id or None, scenario)
        The board's rows in its order (None: a row that did not run, such as ``n/a``), to count each scenario's and
        put them in that order.
    out_dir : path
    users : set of str
        The user's contenders (drawn in bold).
    animate : iterable of str
        The scenarios whose nominal runs are animated.
    """

    def __init__(self, pool, order, out_dir, users, animate):
        self.pool, self.out_dir, self.users, self.animate = pool, Path(out_dir), set(users), list(animate)
        self.place = {key: i for i, key in enumerate(order)}
        self.expected = Counter(sid for _, sid in order)
        self.rows = {sid: [] for sid in self.expected}
        self.stats, self.pictures, self.animations = {}, [], []

    def add(self, row):
        """A row of the board (finished: as the board keeps it); a scenario's work begins with its last."""
        sid = row["scenario"]
        self.rows[sid].append(row)
        if len(self.rows[sid]) == self.expected[sid]:
            self._begin(sid)

    def _begin(self, sid):
        rows = sorted(self.rows[sid], key=lambda r: self.place.get((r.get("case_id"), sid), len(self.place)))
        if sid in paired():
            self.stats[sid] = self.pool.submit(ranking.board_statistics, rows, (sid,))
        if sid in score_plots.RUN_PICTURES:
            self.pictures.append(self.pool.submit(score_plots.plot_scenario, rows, sid, self.out_dir, self.users))
        if sid in self.animate:
            for job in score_plots.animation_jobs(rows, sid, self.out_dir / "animations"):
                self.animations.append((job, self.pool.submit(score_plots.draw_animation, *job)))

    def statistics(self):
        """The statistics of the paired scenarios (:func:`~.ranking.board_statistics`), in their order."""
        result = {}
        for sid in paired():
            if sid in self.stats:
                result.update(self.stats[sid].result())
        return result

    def pictures_drawn(self):
        """The paths of the scenarios' pictures."""
        return [path for path in (future.result() for future in self.pictures) if path]

    def animations_drawn(self):
        """The paths of the animations drawn now, each written in its folder's ledger as it is in."""
        if self.animate:
            (self.out_dir / "animations").mkdir(parents=True, exist_ok=True)  # as drawing them all at the end did
        paths = []
        for job, future in self.animations:
            paths.append(future.result())
            score_plots.record_drawn(job)
        return paths
