"""truss_report.page.top_mechanism: the mechanism margins at the top of the campaign report (ECSS
motorisation): the clause's equation, what of it this model holds, the table of the required and
the available torques, and what was not assessed."""
import numpy as np

from ..judging.mechanism import ECSS_CLAUSE, ECSS_CONFIRM, ECSS_SHORT
from .html import esc, num, table
from .numbers import DASH, fmt, fmt_at, fmt_p, resolution, unit_html


def mechanism_html(m, units):
    """The ECSS table. With no resistance or no declared motor in the file (m.missing,
    m.undeclared) the table is still shown, what cannot be computed "—" and a footnote saying why;
    with no resistance to overcome, a sentence."""
    head = f"<h2 id='mechanism'>Mechanism margins ({esc(ECSS_SHORT)})</h2>"
    if m.n == 0 and not (m.missing or m.undeclared):
        return head + f"<p>Not computed: {esc(m.note)}.</p>"
    rows = mechanism_rows(m, units)
    if m.missing:    # counts of runs would read as results: shown as "—" too
        rows = [[a, f"<td class='num'>{DASH}</td>" if "data-key=\"mech.n" in b else b] for a, b in rows]
    note = ""
    if m.missing or m.undeclared:
        note = f"<p class='small'>— : {esc(m.note)}; the motorisation is not assessed.</p>"
    return head + mechanism_text(m) + table(["", "value"], [[f"<th>{a}</th>", b] for a, b in rows], "kv") + note


def torque_cell(key, v, units):
    """A torque in the drive torque's unit and resolution (page.numbers); data-value in N m."""
    text = units.text("torque", "Nm", v).replace(" ", "\u00a0", 1) if np.isfinite(v) else fmt(v)
    return f'<td class="num" data-key="{esc(key)}" data-value="{repr(float(v))}">{text}</td>'


def percent_cell(key, v, at):
    """A dimensionless margin shown in percent to 10^at of a percent."""
    text = (("+" if v > 0 else "") + fmt_at(100 * v, at) + "\u00a0%") if np.isfinite(v) else fmt(v)
    return f'<td class="num" data-key="{esc(key)}" data-value="{repr(float(v))}">{text}</td>'


def mechanism_rows(m, units):
    """[(label html, value cell)] of the ECSS table (torques in the drive torque's unit)."""
    lo, hi = m.p_below_ci
    vel = m.mode == "velocity"
    avail = ("the scene's motor at the prescribed screw speed" if vel else
             "the motor's stall torque (per run when dispersed)")
    mf = m.mf[np.isfinite(m.mf)] if m.mf is not None else np.array([])
    at_mf = resolution(np.append(mf, m.mf_nominal))
    rows = [
        ["required motorisation factor MF (scene motorisation.factor)", num("mech.mf_required", m.mf_required)],
        ["uncertainty factor k<sub>S</sub> on the spring resistance S (spring_factor; "
         "Table 4-2: spring 1.2)", num("mech.k_uncertainty", m.k_uncertainty)],
        ["factor k<sub>D</sub> on the inertial resistance T<sub>D</sub> (inertia_factor; "
         "equation: 1.25)" + ("" if vel else ": T<sub>D</sub> = 0 in motor mode"), num("mech.k_inertia", m.k_inertia)],
        ["runs considered (ok, finite positive S)", num("mech.n", m.n)],
        ["largest spring resistance S (peak static torque, at the motor)", torque_cell("mech.s_design", m.s_design, units)],
        ["largest inertial resistance T<sub>D</sub> (peak drive − static torque, at the motor)",
         torque_cell("mech.d_design", m.d_design, units)],
        ["largest factored losses L = k<sub>F</sub> F<sub>R</sub> + k<sub>M</sub> H<sub>M</sub> + "
         "k<sub>Y</sub> H<sub>Y</sub> + k<sub>A</sub> H<sub>A</sub> (the scene's [drive] and [motorisation])",
         torque_cell("mech.losses", float(np.max(m.losses)) if m.losses is not None and len(m.losses) else float("nan"),
                     units)],
        ["largest T<sub>min</sub> = MF (k<sub>S</sub> S + L) + k<sub>D</sub> T<sub>D</sub>",
         torque_cell("mech.t_min", m.t_min_design, units)],
        [f"smallest available torque ({avail})", torque_cell("mech.t_avail_min", m.t_avail_min, units)],
        ["smallest achieved MF = (T<sub>available</sub> − k<sub>D</sub> T<sub>D</sub>) / "
         "(k<sub>S</sub> S + L)", num("mech.mf_min", m.mf_min, at=at_mf)],
        ["smallest torque margin T<sub>available</sub> / T<sub>min</sub> − 1",
         percent_cell("mech.tm_min", m.tm_min, resolution([100 * m.tm_min]))],
        ["achieved MF of the nominal run", num("mech.mf_nominal", m.mf_nominal, at=at_mf)],
        ["runs with MF < MF required", num("mech.n_below", m.n_below) if not m.undeclared else f"<td>{DASH}</td>"],
        ["probability, 95 % Clopper-Pearson interval",
         f"<td class='num'>[{fmt_p(lo, lo, hi)}, {fmt_p(hi, lo, hi)}]</td>" if np.isfinite(hi) else f"<td>{DASH}</td>"],
    ]
    if vel:
        rows += [["screw speed ω = 2π v / h", num("mech.omega", m.omega, "rad/s")],
                 ["no-load speed ω<sub>0</sub> of the scene's motor",
                  num("mech.omega0", m.no_load_speed if not m.undeclared else float("nan"), "rad/s")]]
    rows += [[f"<b>stall torque needed</b>: upper {fmt(100 * m.stall_confidence)} % confidence bound of the "
              f"P{fmt(m.stall_level)} of the runs' stall torque that meets the factors (stall torque × "
              "T<sub>min</sub> / T<sub>available</sub>" + (", with that ω<sub>0</sub>" if vel else "") + ")"
              + (f"; no bound: it needs ≥ {m.stall_n_needed} runs" if m.stall_n_needed else ""),
              torque_cell("mech.stall_needed", m.stall_needed, units)],
             ["stall torque of the scene's motor",
              f"<td class='num' data-key='mech.stall_scene' data-value='{repr(m.stall_scene)}'>"
              + (f"{fmt(m.stall_scene / units.get('torque', 'Nm')[1])}\u00a0{unit_html(units.get('torque', 'Nm')[0])}"
                 if not m.undeclared else DASH) + "</td>"]]
    return rows


def mechanism_text(m):
    """The clause's equation and what of it this model holds, with the source."""
    vel = m.mode == "velocity"
    return ("<p>T<sub>min</sub> = 2 (1.1 I + 1.2 S + 1.5 H<sub>M</sub> + 3 F<sub>R</sub> + "
            "3 H<sub>Y</sub> + 3 H<sub>A</sub> + 3 H<sub>D</sub>) + 1.25 T<sub>D</sub> + "
            "T<sub>L</sub> (clause 4.7.5.3.1; uncertainty factors of Table 4-2, theoretical "
            "column). Torques are at the motor shaft, through the scene's drive train (gear ratio and "
            "efficiencies); with the ideal train, the screws' torque, the three together. The simulator "
            "computes the check per run (/runs/motorisation_required_torque_Nm); this rigid, frictionless model has "
            "the spring resistance S (the diagonals: the torque that holds the mast at rest along "
            "its path)"
            + (" and, with the prescribed speed as the acceleration requirement, the inertial "
               "resistance T<sub>D</sub> (drive torque minus S). " if vel else
               "; the motor drive has no specified acceleration, so T<sub>D</sub> = 0 and the "
               "motor's stall torque is compared with the factored springs. ")
            + "Each is its peak over the run, so T<sub>min</sub> is an upper bound. The drive train's "
            "losses F<sub>R</sub>, H<sub>M</sub>, H<sub>Y</sub>, H<sub>A</sub> are the scene's [drive] "
            "torques with the [motorisation] factors; I, H<sub>D</sub> and T<sub>L</sub> have no "
            "counterpart in the model.</p><p class='small'>Source: "
            f"{esc(ECSS_CLAUSE)}. {esc(ECSS_CONFIRM)}</p>")
