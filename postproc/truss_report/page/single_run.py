"""truss_report.page.single_run: the single-run report: status, summary, per-bay table and the
paper's Fig. 4 and Fig. 5."""
from functools import partial

import os

import numpy as np

from .figures_run import fig4, fig5, fig5_zoom, fig_frame_heights
from .html import esc, html_page, num, table, unit_label
from .numbers import MOST, message_text, unit_text
from .render import Report


def single_run_report(page, run):
    """Summary table, per-bay table and paper Fig. 4 / Fig. 5 (no verdict)."""
    rows = []
    for name, v, u in run.summary:
        if isinstance(v, str):
            rows.append([f"<code>{name}</code>", esc(v), ""])
        else:
            rows.append([f"<code>{name}</code>", num(f"summary.{name}", v, digits=MOST), esc(unit_text(u))])
    status, message = run.status, run.message
    meta = [("software", f"truss {esc(run.software_version)}, git revision "
                         f"<code>{esc(run.git_revision)}</code>"),
            ("written (UTC)", esc(run.created_utc)),
            ("status", f"<b>{esc(status)}</b>" + (f": {esc(message_text(message))}" if message else ""))]
    parts = [table(["", ""], [[f"<th>{k}</th>", v] for k, v in meta], "kv"),
             f"<details><summary>scene_toml</summary><pre>{esc(run.scene_toml)}</pre>"
             "</details>",
             "<section id='summary'><h2>Summary</h2>",
             table(["field", "value", "units"], rows, "narrow"), "</section>",
             single_run_bays(run), single_run_figures(page, run.figures)]
    title = f"Single-run report: {os.path.basename(run.path)} (status {status})"
    doc = [("run", f"single run, status <b>{esc(status)}</b>"),
           ("tool", f"truss {esc(run.software_version)}, git revision "
                    f"<code>{esc(run.git_revision)}</code>"),
           ("verdict", "none: a single run is not judged")]
    return Report(html_page(title, run.path, run.sha256, "\n".join(parts), doc), [], None)


def single_run_bays(run):
    b = run.bays
    if not b:
        return ""
    fields = [k for k in b if k != "bay"]
    rows = [[str(bay)] + [num(f"bays.{k}.bay{bay}", float(b[k][i]), digits=MOST) for k in fields]
            for i, bay in enumerate(b["bay"])]
    return ("<section id='bays'><h2>Per bay</h2><details><summary>per-bay table "
            f"({len(b['bay'])} bays)</summary>"
            + table(["bay"] + [f"<code>{k}</code>{unit_label(run.bay_units[k])}"
                               for k in fields], rows)
            + "</details></section>")


def single_run_figures(page, run):
    head = "<section id='figures'><h2>Figures (paper Fig. 4 and Fig. 5)</h2>"
    if run is None:
        return (head + "<p class='note'>The file has no <code>/history</code>: run truss-sim "
                "with <code>run.output_step_s &gt; 0</code> for the figures.</p></section>")
    bay = run.n_bays
    h = run.history
    sel = h["bay"] == bay
    parts = [head]
    if np.any(np.isfinite(h["hinge_x_m"][sel]) & np.isfinite(h["hinge_y_m"][sel])):
        parts.append(page.figure(partial(fig4, page.plt, run, bay),
                                 f"fig4_hinge_trajectory_bay{bay}.png",
                                 f"hinge trajectory of bay {bay} (paper Fig. 4)", "half"))
    else:
        parts.append(f"<p class='note'>No hinge samples of bay {bay}: no Fig. 4.</p>")
    parts.append(page.figure(partial(fig5, page.plt, run), "fig5_drive_and_pin_force.png",
                             "drive force and rail pin force against time (paper Fig. 5)"))
    if np.any(sel):
        parts.append(page.figure(partial(fig5_zoom, page.plt, run, bay), f"fig5_bay{bay}_zoom.png",
                                 f"the same in the stage of bay {bay}"))
    if "frame_height_m" in h:
        parts.append(page.figure(partial(fig_frame_heights, page.plt, run), "frame_heights.png",
                                 "heights of the frames against time (free stack)"))
    parts.append("</section>")
    return "\n".join(parts)
