"""A corpus of bad inputs: (name, config text, extra files, CLI args, expected message regex).

Each must give exit code 2, one line ``rbrdo: error: ...`` naming the field (or file), and
leave no run folder. ``{dir}`` in a config is replaced by the test's folder (for files).
"""

from __future__ import annotations

STUDY = """[experiment]
name = "s"
kind = "study"
seed = 1
[surrogate]
n_doe = 20
n_jobs = 1
n_start = 1
[design_model]
n_train = 10
n_validate = 2
[deterministic]
resonance = "none"
[optimization]
p_targets = [0.10, 0.05]
n_theta = 40
pop_size = 8
n_gen = 3
n_jobs = 1
[verification]
n_theta = 6
n_jobs = 1
[report]
n_speeds = 20
campbell_speeds = 4
n_modes = 2
"""

SPINDLE = """[experiment]
name = "r"
kind = "spindle_report"
[report]
designs = { a = [3000.0, 300.0, 80.0] }
n_speeds = 20
campbell_speeds = 3
n_modes = 2
"""

VALIDATION = """[experiment]
name = "v"
kind = "surrogate_validation"
seed = 1
[surrogate]
n_doe = 14
n_jobs = 1
[validation]
n_test = 10
n_theta = 20
[validation.designs]
a = [2000.0, 330.0, 75.0]
"""

GEOMETRY_OK = """[geometry]
tool_tip_mm = 0.0
[[geometry.sections]]
length_mm = 100.0
outer_diameter_mm = 60.0
tag = "span"
[[geometry.sections]]
length_mm = 300.0
outer_diameter_mm = 60.0
tag = "span"
[[geometry.bearings]]
name = "front"
position_mm = 100.0
law = {type = "constant", k_N_per_m = 2e8}
[[geometry.bearings]]
name = "rear"
position_mm = 400.0
law = {type = "constant", k_N_per_m = 2e8}
[[geometry.unbalances]]
position_mm = 0.0
magnitude_kgm = 1e-5
"""


RIG = """[experiment]
name = "g"
kind = "rig"
[rig.campaign]
speeds_rpm = [6000.0]
repeats = 1
duration_s = 0.1
runup = [1000.0, 2000.0, 0.5]
impacts_per_direction = 0
"""

RIG_VAL = """[experiment]
name = "w"
kind = "validation"
[validation]
n_replications = 4
ramps = 0
[designs]
a = [2000.0, 500.0, 65.0]
b = [3000.0, 350.0, 75.0]
"""

LOOP = """[experiment]
name = "l"
kind = "end_to_end"
[spindle]
geometry = "credible"
[response]
kind = "peak_unbalance"
[limit]
delta_lim_um = 1.0
[surrogate]
structure = "fe"
[optimization]
p_targets = [0.10]
strategies = []
n_theta = 20
pop_size = 8
n_gen = 2
n_jobs = 1
[rig.campaign]
speeds_rpm = { start = 8000.0, stop = 24000.0, num = 8 }
repeats = 6
trial_unbalance = [0.0, 5e-5, 0.0]
[validation]
delta_lim_um = 1.0
"""

DISC = """[experiment]
name = "d"
kind = "discrepancy"
[discrepancy]
n_draws = 100
[rig]
figures = false
[rig.campaign]
speeds_rpm = { start = 1000.0, stop = 24000.0, num = 10 }
repeats = 2
duration_s = 0.4
runup = []
impacts_per_direction = 0
"""

#: the discrepancy kind on measured data: a data folder (phasors.csv) in the test's folder
DISC_DATA = DISC.split("[rig]")[0] + "[data]\npath = 'm'\n"
PHASORS = "run,speed_rpm,channel,re_m,im_m\n0,1000.0,front_x,1e-6,0.0\n"


def _set(base: str, table: str, line: str) -> str:
    """Add ``line`` at the top of ``[table]`` (the table is created if missing)."""
    head = f"[{table}]\n"
    if head in base:
        return base.replace(head, head + line + "\n", 1)
    return base + f"\n{head}{line}\n"


def _sub(base: str, old: str, new: str) -> str:
    assert old in base, old
    return base.replace(old, new, 1)


def S(table: str, line: str) -> str:          # noqa: N802 - short names keep the corpus legible
    return _set(STUDY, table, line)


def PU(table: str, line: str) -> str:       # noqa: N802 - the random-unbalance peak
    return _set(_set(STUDY, "response", "kind = 'peak_unbalance'"), table, line)


def R(table: str, line: str) -> str:          # noqa: N802
    return _set(SPINDLE, table, line)


def V(table: str, line: str) -> str:          # noqa: N802
    return _set(VALIDATION, table, line)


def G(table: str, line: str) -> str:          # noqa: N802
    return _set(RIG, table, line)


def W(table: str, line: str) -> str:          # noqa: N802
    return _set(RIG_VAL, table, line)


def E(table: str, line: str) -> str:          # noqa: N802 - the end-to-end loop
    return _set(LOOP, table, line)
IDENT = """[experiment]
name = "i"
kind = "identification"
[identification]
source = "."
n_boot = 20
"""

#: a steady-record dataset without trial-weight runs (the record file is not read)
DS_NO_TRIAL = {
    "dataset.json": "{}",
    "index.jsonl": '{"id": "a", "kind": "steady", "file": "a.npz", "speed_rpm": 6000.0, '
                   '"labels": {"run": 0, "repeat": 0}}\n',
    "a.npz": "not read",
}


def ID(line: str) -> str:                     # noqa: N802
    return _set(IDENT, "identification", line)


def D(table: str, line: str) -> str:          # noqa: N802
    return _set(DISC, table, line)


ARR = r"must be an array of"
INT = r"must be an integer"
NUM = r"must be a number"
BOOL = r"must be true or false"
STR = r"must be a string"
TAB = r"must be a table"

#: (id, config, files {name: text}, extra CLI args, regex)
CORPUS: list[tuple[str, str, dict[str, str], list[str], str]] = [
    # ------------------------------------------------------------------ the file itself
    ("toml_syntax", "[experiment\n", {}, [], r"config file '.*exp.toml' is not valid TOML"),
    ("no_experiment", "[report]\nn_speeds = 3\n", {}, [], r"missing \[experiment\] table"),
    ("experiment_not_table", "experiment = 5\n", {}, [], r"missing \[experiment\] table"),
    ("binary", "\x00\x01\x02", {}, [], r"is not valid TOML"),
    ("empty", "", {}, [], r"missing \[experiment\] table"),
    # ------------------------------------------------------------------ [experiment]
    ("kind_missing", "[experiment]\nname = 'x'\n", {}, [], r"experiment.kind is missing"),
    ("name_missing", "[experiment]\nkind = 'study'\n", {}, [], r"experiment.name is missing"),
    ("kind_unknown", "[experiment]\nname = 'x'\nkind = 'nope'\n", {}, [],
     r"experiment.kind = 'nope' is not allowed: unknown experiment kind; known: .*study"),
    ("kind_int", "[experiment]\nname = 'x'\nkind = 3\n", {}, [],
     r"experiment.kind = 3 is not allowed: " + STR),
    ("name_int", "[experiment]\nname = 3\nkind = 'study'\n", {}, [],
     r"experiment.name = 3 is not allowed: " + STR),
    ("name_escape", _sub(SPINDLE, 'name = "r"', 'name = "../../x"'), {}, [],
     r"experiment.name = '../../x' is not allowed: must be 1-128 letters"),
    ("name_slash", _sub(SPINDLE, 'name = "r"', 'name = "a/b"'), {}, [],
     r"experiment.name = 'a/b' is not allowed"),
    ("name_dot", _sub(SPINDLE, 'name = "r"', 'name = "."'), {}, [],
     r"experiment.name = '.' is not allowed"),
    ("name_empty", _sub(SPINDLE, 'name = "r"', 'name = ""'), {}, [],
     r"experiment.name = '' is not allowed"),
    ("seed_neg", R("experiment", "seed = -3"), {}, [], r"experiment.seed = -3 is not allowed"),
    ("seed_float", R("experiment", "seed = 1.5"), {}, [],
     r"experiment.seed = 1.5 is not allowed: " + INT),
    ("seed_str", R("experiment", "seed = '7'"), {}, [],
     r"experiment.seed = '7' is not allowed: " + INT),
    ("seed_bool", R("experiment", "seed = true"), {}, [],
     r"experiment.seed = True is not allowed: " + INT),
    ("experiment_unknown_key", R("experiment", "colour = 1"), {}, [],
     r"unknown key experiment.colour; allowed: \['description', 'kind', 'name'"),
    ("results_dir_int", R("experiment", "results_dir = 5"), {}, [],
     r"experiment.results_dir = 5 is not allowed: " + STR),
    ("description_list", R("experiment", "description = ['a']"), {}, [],
     r"experiment.description = \['a'\] is not allowed: " + STR),
    # ------------------------------------------------------------------ unknown tables
    ("reprot", SPINDLE.replace("[report]", "[reprot]"), {}, [],
     r"unknown table reprot; allowed: \['report', 'spindle'\]"),
    ("study_unknown_table", S("optimisation", "n_gen = 3"), {}, [],
     r"unknown table optimisation; allowed: \[.*'optimization'"),
    ("validation_unknown_table", V("design_model", "n_train = 10"), {}, [],
     r"unknown table design_model; allowed"),
    ("validation_response_kind", V("response", "kind = 'peak_unbalanced'"), {}, [],
     r"response.kind = 'peak_unbalanced' is not allowed: must be one of"),
    ("top_level_key", "top = 1\n" + SPINDLE, {}, [], r"unknown key top"),
    ("table_is_scalar", "report = 3\n" + SPINDLE.split("[report]")[0], {}, [],
     r"report = 3 is not allowed: " + TAB),
    # ------------------------------------------------------------------ [spindle]
    ("geometry_int", R("spindle", "geometry = 5"), {}, [],
     r"spindle.geometry = 5 is not allowed: " + STR),
    ("geometry_missing_file", R("spindle", "geometry = 'nope.toml'"), {}, [],
     r"spindle.geometry file '.*nope.toml' does not exist"),
    ("geometry_missing_json", R("spindle", "geometry = 'nope.json'"), {}, [],
     r"spindle.geometry file '.*nope.json' does not exist"),
    ("geometry_suffix", R("spindle", "geometry = 'g.yaml'"), {"g.yaml": "a: 1"}, [],
     r"spindle.geometry = 'g.yaml' is not allowed: give a built-in spindle \['credible', "
     r"'reference'\] or a .toml/.json geometry file$"),
    ("geometry_json_syntax", R("spindle", "geometry = 'g.json'"), {"g.json": "{bad"}, [],
     r"spindle.geometry file '.*g.json' is not valid JSON"),
    ("geometry_json_list", R("spindle", "geometry = 'g.json'"), {"g.json": "[1, 2]"}, [],
     r"spindle.geometry file '.*g.json': geometry = \[1, 2\] is not allowed: must be a table"),
    ("geometry_toml_syntax", R("spindle", "geometry = 'g.toml'"), {"g.toml": "[geometry"}, [],
     r"spindle.geometry file '.*g.toml' is not valid TOML"),
    ("geometry_bearing_no_name", R("spindle", "geometry = 'g.toml'"),
     {"g.toml": GEOMETRY_OK.replace('name = "rear"\n', "")}, [],
     r"spindle.geometry file '.*g.toml': geometry.bearings\[1\].name is missing"),
    ("geometry_unknown_key", R("spindle", "geometry = 'g.toml'"),
     {"g.toml": GEOMETRY_OK.replace("tool_tip_mm = 0.0", "tool_tip = 0.0")}, [],
     r"spindle.geometry file '.*g.toml': unknown key geometry.tool_tip; allowed"),
    ("geometry_zero_unbalance", R("spindle", "geometry = 'g.toml'"),
     {"g.toml": GEOMETRY_OK.replace("magnitude_kgm = 1e-5", "magnitude_kgm = 0.0")}, [],
     r"every unbalance is zero"),
    ("geometry_no_unbalance", R("spindle", "geometry = 'g.toml'"),
     {"g.toml": GEOMETRY_OK.split("[[geometry.unbalances]]")[0]}, [],
     r"every unbalance is zero \(or there is none\)"),
    ("geometry_bad_law", R("spindle", "geometry = 'g.toml'"),
     {"g.toml": GEOMETRY_OK.replace('type = "constant", k_N', 'type = "magic", k_N')}, [],
     r"spindle.geometry file '.*g.toml': geometry.bearings\[0\].law.type = 'magic' is not"),
    ("grade_str", R("spindle", "balance_grade_mm_s = 'G2.5'"), {}, [],
     r"spindle.balance_grade_mm_s = 'G2.5' is not allowed: " + NUM),
    ("grade_neg", R("spindle", "balance_grade_mm_s = -1"), {}, [],
     r"spindle.balance_grade_mm_s = -1.0 is not allowed: must lie in \[0.16, 4000.0\]"),
    ("grade_nan", R("spindle", "balance_grade_mm_s = nan"), {}, [],
     r"spindle.balance_grade_mm_s = nan is not allowed: must be a finite number"),
    ("grade_inf", R("spindle", "balance_grade_mm_s = inf"), {}, [],
     r"spindle.balance_grade_mm_s = inf is not allowed: must be a finite number"),
    ("grade_with_file", R("spindle", "geometry = 'g.toml'\nbalance_grade_mm_s = 2.5"),
     {"g.toml": GEOMETRY_OK}, [], r"spindle.balance_grade_mm_s applies only to geometry"),
    ("effects_str", R("spindle", "effects = 'none'"), {}, [],
     r"spindle.effects = 'none' is not allowed: " + ARR),
    ("effects_unknown", R("spindle", "effects = [{name = 'warp'}]"), {}, [],
     r"spindle.effects\[0\].name = 'warp' is not allowed: unknown effect 'warp'; known: .*"
     r"speed_softening"),
    ("effects_no_name", R("spindle", "effects = [{a = 0.1}]"), {}, [],
     r"spindle.effects\[0\].name = None is not allowed: unknown effect None"),
    ("effects_bad_param", R("spindle", "effects = [{name = 'speed_softening', b = 1}]"), {},
     [], r"unknown key spindle.effects\[0\].b; allowed: \['a', 'bearings'"),
    ("effects_scalar_item", R("spindle", "effects = [3]"), {}, [],
     r"spindle.effects\[0\] = 3 is not allowed: " + TAB),
    ("design_map_int", R("spindle", "design_map = 5"), {}, [],
     r"spindle.design_map = 5 is not allowed: " + TAB),
    ("design_map_key", R("spindle", "design_map = {lowr = [1.0, 2.0, 3.0]}"), {}, [],
     r"unknown key spindle.design_map.lowr; allowed: \['lower', 'preload_bearing'"),
    ("design_map_short", R("spindle", "design_map = {lower = [1000.0, 300.0]}"), {}, [],
     r"spindle.design_map.lower = \[1000.0, 300.0\] is not allowed: must be an array of 3"),
    ("design_map_order", R("spindle", "design_map = {lower = [3000.0, 300.0, 50.0], "
                           "upper = [1000.0, 750.0, 80.0]}"), {}, [],
     r"spindle.design_map: design bounds for preload_N = \[3000.0, 1000.0\] are not allowed"),
    ("design_map_bore", R("spindle", "design_map = {lower = [1000.0, 300.0, 25.0]}"), {}, [],
     r"spindle.design_map.lower\[2\] = 25.0 is not allowed: .*exceed the bore 30.0 mm"),
    ("baseline_outside", R("spindle", "baseline = [9000.0, 500.0, 65.0]"), {}, [],
     r"spindle.baseline: design preload_N = 9000.0 is not allowed: must lie in"),
    ("baseline_str", R("spindle", "baseline = '2000,500,65'"), {}, [],
     r"spindle.baseline = '2000,500,65' is not allowed: " + ARR),
    ("theta_bearings_str", R("spindle", "theta_bearings = 'front'"), {}, [],
     r"spindle.theta_bearings = 'front' is not allowed: " + ARR),
    ("theta_bearings_dup", R("spindle", "theta_bearings = ['front', 'front']"), {}, [],
     r"theta_bearings = \['front', 'front'\] is not allowed.*appears twice"),
    ("theta_bearings_unknown", R("spindle", "theta_bearings = ['nose']"), {}, [],
     r"spindle.theta_bearings = \['nose'\] is not allowed: 'nose' is not a bearing"),
    ("spindle_unknown_key", R("spindle", "geometri = 'reference'"), {}, [],
     r"unknown key spindle.geometri; allowed: \['balance_grade_mm_s', 'baseline'"),
    # ------------------------------------------------------------------ [report] (spindle)
    ("n_speeds_1", _sub(SPINDLE, "n_speeds = 20", "n_speeds = 1"), {}, [],
     r"report.n_speeds = 1 is not allowed: must be an integer >= 2"),
    ("n_speeds_float", _sub(SPINDLE, "n_speeds = 20", "n_speeds = 1e12"), {}, [],
     r"report.n_speeds = 1000000000000.0 is not allowed: " + INT),
    ("n_speeds_huge", _sub(SPINDLE, "n_speeds = 20", "n_speeds = 1000000000000"), {}, [],
     r"report.n_speeds = 1000000000000 is not allowed: .* GB of memory, more than the"),
    ("n_modes_0", _sub(SPINDLE, "n_modes = 2", "n_modes = 0"), {}, [],
     r"report.n_modes = 0 is not allowed"),
    ("include_box_str", R("report", "include_box = 'yes'"), {}, [],
     r"report.include_box = 'yes' is not allowed: " + BOOL),
    ("include_box_int", R("report", "include_box = 1"), {}, [],
     r"report.include_box = 1 is not allowed: " + BOOL),
    ("designs_str", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }", "designs = 'a'"),
     {}, [], r"report.designs = 'a' is not allowed: must be a (valid dictionary|table)"),
    ("designs_empty", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }",
                           "designs = {}"), {}, [], r"report.designs = \{\} is not allowed"),
    ("design_outside", _sub(SPINDLE, "a = [3000.0, 300.0, 80.0]", "a = [9000.0, 300.0, 80.0]"),
     {}, [], r"report.designs.a: design preload_N = 9000.0 is not allowed: must lie in"),
    ("design_short", _sub(SPINDLE, "a = [3000.0, 300.0, 80.0]", "a = [3000.0, 300.0]"),
     {}, [], r"report.designs.a = \[3000.0, 300.0\] is not allowed: must be an array of 3"),
    ("design_str_item", _sub(SPINDLE, "a = [3000.0, 300.0, 80.0]", "a = [3000.0, 'x', 80.0]"),
     {}, [], r"report.designs.a\[1\] = 'x' is not allowed: " + NUM),
    ("report_unknown_key", R("report", "n_speed = 3"), {}, [],
     r"unknown key report.n_speed; allowed: \['campbell_speeds', 'designs'"),
    # ------------------------------------------------------------------ [uncertainty]
    ("mean_negative", S("uncertainty", "mean = [-1.0, 1.0]"), {}, [],
     r"uncertainty.mean\[0\] = -1.0 is not allowed: a stiffness factor must stay positive"),
    ("mean_negative_with_std", S("uncertainty", "mean = [-1.0, 1.0]\nstd = [0.015, 0.033]"),
     {}, [], r"uncertainty.mean\[0\] = -1.0 is not allowed: a stiffness factor must stay "
     r"positive"),
    ("mean_zero_with_std", S("uncertainty", "mean = [1.0, 0.0]\nstd = [0.015, 0.033]"),
     {}, [], r"uncertainty.mean\[1\] = 0.0 is not allowed"),
    ("mean_str", S("uncertainty", "mean = '1,1'"), {}, [],
     r"uncertainty.mean = '1,1' is not allowed: " + ARR),
    ("mean_len", S("uncertainty", "mean = [1.0, 1.0, 1.0]"), {}, [],
     r"uncertainty.mean = \[1.0, 1.0, 1.0\] is not allowed: need 2 values"),
    ("std_neg", S("uncertainty", "std = [0.05, -0.1]"), {}, [],
     r"uncertainty.std\[1\] = -0.1 is not allowed"),
    ("std_zero", S("uncertainty", "std = [0.05, 0.0]"), {}, [],
     r"uncertainty.std\[1\] = 0.0 is not allowed"),
    ("std_wide", S("uncertainty", "std = [0.5, 0.06]"), {}, [],
     r"uncertainty.mean\[0\] = 1.0 is not allowed: .*need mean > 8 std = 4"),
    ("corr_not_pd", S("uncertainty", "corr = [[1.0, 2.0], [2.0, 1.0]]"), {}, [],
     r"uncertainty.corr: "),
    ("corr_str", S("uncertainty", "corr = 'none'"), {}, [],
     r"uncertainty.corr = 'none' is not allowed: " + ARR),
    ("uncertainty_key", S("uncertainty", "sigma = [0.1, 0.1]"), {}, [],
     r"unknown key uncertainty.sigma"),
    ("distribution_bad", S("uncertainty", "distribution = 'weibull'"), {}, [],
     r"uncertainty.distribution = 'weibull' is not allowed: must be one of"),
    ("lognormal_mean_neg", S("uncertainty", "distribution = 'lognormal'\nmean = [-1.0, 1.0]"),
     {}, [], r"uncertainty.mean\[0\] = -1.0 is not allowed"),
    ("unbalance_wrong_kind", S("uncertainty", "unbalance = {magnitude = 'disk'}"), {}, [],
     r"uncertainty.unbalance is not allowed with response.kind = 'peak'"),
    ("thermal_wrong_kind", S("uncertainty", "thermal_max = 0.5"), {}, [],
     r"uncertainty.thermal_max is not allowed with response.kind = 'peak'"),
    ("thermal_neg", PU("uncertainty", "thermal_max = -0.5"), {}, [],
     r"uncertainty.thermal_max = -0.5 is not allowed"),
    ("thermal_str", PU("uncertainty", "thermal_max = 'hot'"), {}, [],
     r"uncertainty.thermal_max = 'hot' is not allowed: " + NUM),
    ("magnitude_bad", PU("uncertainty.unbalance", "magnitude = 'max'"), {}, [],
     r"uncertainty.unbalance.magnitude = 'max' is not allowed: must be one of"),
    ("relative_phase_str", PU("uncertainty.unbalance", "relative_phase = 'yes'"), {}, [],
     r"uncertainty.unbalance.relative_phase = 'yes' is not allowed: " + BOOL),
    ("planes_one", PU("uncertainty.unbalance", "planes = [{grade_mm_s = 2.5}]"), {}, [],
     r"uncertainty.unbalance: .*1 planes, the geometry has 2"),
    ("planes_disk", PU("uncertainty.unbalance", "planes = [{disks = ['spoke']}, {}]"), {}, [],
     r"uncertainty.unbalance: .*'spoke' is not a disk"),
    ("planes_grade", PU("uncertainty.unbalance", "planes = [{grade_mm_s = -2.5}, {}]"), {}, [],
     r"uncertainty.unbalance.planes\[0\].grade_mm_s = -2.5 is not allowed"),
    ("planes_rest_twice", PU("uncertainty.unbalance", "planes = [{}, {}]"), {}, [],
     r"uncertainty.unbalance: .*at most one plane may take 'the rest of the rotor'"),
    ("unbalance_key", PU("uncertainty.unbalance", "phase = 'random'"), {}, [],
     r"unknown key uncertainty.unbalance.phase; allowed"),
    ("pu_resonance", PU("surrogate", "structure = 'resonance'"), {}, [],
     r"surrogate.structure = 'resonance' is not allowed with response.kind = "
     r"'peak_unbalance': .*fixed unbalance.*; use 'substructure', 'global' or 'fe'"),
    ("pu_speed", PU("response", "speed_rpm = 20000.0"), {}, [],
     r"response.speed_rpm = 20000.0 is not allowed with kind = 'peak_unbalance'"),
    ("geometry_name", S("spindle", "geometry = 'credibel'"), {}, [],
     r"spindle.geometry = 'credibel' is not allowed: give a built-in spindle \['credible', "
     r"'reference'\] or a .toml/.json geometry file; did you mean 'credible'\?"),
    ("geometry_name_ref", S("spindle", "geometry = 'refrence'"), {}, [],
     r"spindle.geometry = 'refrence' is not allowed: .*; did you mean 'reference'\?"),
    ("geometry_name_credibl", R("spindle", "geometry = 'credibl'"), {}, [],
     r"spindle.geometry = 'credibl' is not allowed: .*; did you mean 'credible'\?"),
    ("credible_grade", S("spindle", "geometry = 'credible'\nbalance_grade_mm_s = 0.0"), {}, [],
     r"spindle.balance_grade_mm_s = 0.0 is not allowed"),
    # ------------------------------------------------------------------ [[constraints]]
    ("constraint_expr", S("constraints", "") .replace("[constraints]", "[[constraints]]")
     + "name = 'c'\nexpression = '__import__(1)'\n", {}, [],
     r"constraints\[0\]: constraint 'c': expression '__import__\(1\)' is not allowed"),
    ("constraint_name", STUDY + "[[constraints]]\nname = 'c'\nexpression = 'span / 9'\n", {},
     [], r"constraints\[0\]: .*unknown name 'span' \(design variables: preload_N, span_mm"),
    ("constraint_missing", STUDY + "[[constraints]]\nname = 'c'\n", {}, [],
     r"constraints\[0\].expression is missing"),
    ("constraint_scale", STUDY + "[[constraints]]\nname = 'c'\nexpression = 'span_mm <= 700'"
     "\nscale = 0.0\n", {}, [], r"constraints\[0\]: .*scale = 0.0 is not allowed"),
    ("constraint_dup", STUDY + "[[constraints]]\nname = 'c'\nexpression = 'span_mm <= 700'\n"
     "[[constraints]]\nname = 'c'\nexpression = 'span_mm <= 600'\n", {}, [],
     r"constraints\[1\].name = 'c' is not allowed: taken"),
    ("constraint_key", STUDY + "[[constraints]]\nname = 'c'\nexpression = 'span_mm <= 7'\n"
     "limit = 3.0\n", {}, [], r"unknown key constraints\[0\].limit"),
    ("constraints_table", STUDY + "[constraints]\nname = 'c'\n", {}, [],
     r"constraints = .* is not allowed: must be an array of tables"),
    # ------------------------------------------------------------------ [limit], [response]
    ("delta_neg", S("limit", "delta_lim_um = -1.5"), {}, [],
     r"limit.delta_lim_um = -1.5 is not allowed: must be a finite number > 0"),
    ("delta_str", S("limit", "delta_lim_um = '1.5 um'"), {}, [],
     r"limit.delta_lim_um = '1.5 um' is not allowed: " + NUM),
    ("limit_key", S("limit", "delta_lim = 1.5"), {}, [], r"unknown key limit.delta_lim"),
    ("response_kind", S("response", "kind = 'rms'"), {}, [],
     r"response.kind = 'rms' is not allowed: must be one of \['peak', 'at_speed', "
     r"'peak_unbalance'\]"),
    ("response_no_speed", S("response", "kind = 'at_speed'"), {}, [],
     r"response.speed_rpm = None is not allowed"),
    ("response_speed_str", S("response", "kind = 'at_speed'\nspeed_rpm = 'fast'"), {}, [],
     r"response.speed_rpm = 'fast' is not allowed: " + NUM),
    ("response_speed_range", S("response", "kind = 'at_speed'\nspeed_rpm = 90000.0"), {}, [],
     r"response.speed_rpm = 90000.0 is not allowed: must lie in the spindle's speed range"),
    ("response_peak_speed", S("response", "speed_rpm = 20000.0"), {}, [],
     r"response.speed_rpm = 20000.0 is not allowed with kind = 'peak'"),
    # ------------------------------------------------------------------ [surrogate]
    ("structure_unknown", S("surrogate", "structure = 'neural'"), {}, [],
     r"surrogate.structure = 'neural' is not allowed: must be one of \['fe', 'global'"),
    ("structure_int", S("surrogate", "structure = 1"), {}, [],
     r"surrogate.structure = 1 is not allowed: must be one of"),
    ("n_doe_small", _sub(STUDY, "n_doe = 20", "n_doe = 3"), {}, [],
     r"surrogate.n_doe = 3 is not allowed: must be an integer >= 7"),
    ("n_doe_float", _sub(STUDY, "n_doe = 20", "n_doe = 20.0"), {}, [],
     r"surrogate.n_doe = 20.0 is not allowed: " + INT),
    ("n_doe_huge", _sub(STUDY, "n_doe = 20", "n_doe = 10000000"), {}, [],
     r"surrogate.n_doe = 10000000 is not allowed: .* GB of memory"),
    ("transform_bad", S("surrogate", "transform = 'sqrt'"), {}, [],
     r"surrogate.transform = 'sqrt' is not allowed: must be one of \['log', 'none'\]"),
    ("surrogate_name_bad", S("surrogate", "surrogate = 'nn'"), {}, [],
     r"surrogate.surrogate = 'nn' is not allowed: must be one of"),
    ("theta_bounds_order", S("surrogate", "theta_box = 'bounds'\ntheta_bounds = [1.5, 0.5]"),
     {}, [], r"surrogate.theta_bounds = \(1.5, 0.5\) is not allowed"),
    ("theta_bounds_str", S("surrogate", "theta_bounds = '0.5-1.5'"), {}, [],
     r"surrogate.theta_bounds = '0.5-1.5' is not allowed: " + ARR),
    ("al_str", S("surrogate", "active_learning = 'yes'"), {}, [],
     r"surrogate.active_learning = 'yes' is not allowed: " + BOOL),
    ("al_frac", S("surrogate", "al_uncertain_frac = 2.0"), {}, [],
     r"surrogate.al_uncertain_frac = 2.0 is not allowed: must lie in \[0.0, 1.0\]"),
    ("backend_bad", S("surrogate", "backend = 'mpi'"), {}, [],
     r"surrogate.backend = 'mpi' is not allowed: must be one of"),
    ("n_jobs_zero", _sub(STUDY, "n_doe = 20\nn_jobs = 1", "n_doe = 20\nn_jobs = 0"), {}, [],
     r"surrogate.n_jobs = 0 is not allowed"),
    ("surrogate_key_typo", S("surrogate", "n_dooe = 20"), {}, [],
     r"unknown key surrogate.n_dooe; allowed: \[.*'n_doe'"),
    ("fe_with_n_doe", S("surrogate", "structure = 'fe'"), {}, [],
     r"unknown key surrogate.n_doe; allowed: \['fe_method'\]"),
    ("res_with_transform", S("surrogate", "structure = 'resonance'\ntransform = 'none'"), {}, [],
     r"unknown key surrogate.transform"),
    ("res_at_speed", S("surrogate", "structure = 'resonance'") + "[response]\nkind = "
     "'at_speed'\nspeed_rpm = 24000.0\n", {}, [],
     r"surrogate.structure = 'resonance' is not allowed with response.kind = 'at_speed'"),
    ("res_bg_only", S("surrogate", "structure = 'resonance'\nres_bg_only_r = 0.99"), {}, [],
     r"surrogate.res_bg_only_r = 0.99 is not allowed: must be <= res_bg_r_max"),
    ("sub_speeds", S("surrogate", "structure = 'substructure'\nsub_n_speeds = 1"), {}, [],
     r"surrogate.sub_n_speeds = 1 is not allowed"),
    # ------------------------------------------------------------------ [design_model]
    ("dm_small", _sub(STUDY, "n_train = 10", "n_train = 2"), {}, [],
     r"design_model.n_train = 2 is not allowed: must be an integer >= 8"),
    ("dm_str", _sub(STUDY, "n_train = 10", "n_train = 'ten'"), {}, [],
     r"design_model.n_train = 'ten' is not allowed: " + INT),
    ("dm_key", S("design_model", "n_test = 3"), {}, [], r"unknown key design_model.n_test"),
    # ------------------------------------------------------------------ [deterministic]
    ("stress_str", S("deterministic", "stress = 'no'"), {}, [],
     r"deterministic.stress = 'no' is not allowed: " + BOOL),
    ("stress_int", S("deterministic", "stress = 0"), {}, [],
     r"deterministic.stress = 0 is not allowed: " + BOOL),
    ("yield_neg", S("deterministic", "yield_strength_pa = -1.0"), {}, [],
     r"deterministic.yield_strength_pa = -1.0 is not allowed"),
    ("resonance_bad", _sub(STUDY, 'resonance = "none"', 'resonance = "campbell"'), {}, [],
     r"deterministic.resonance = 'campbell' is not allowed: must be one of"),
    ("search_factor_neg", S("deterministic", "search_factor = -1.5"), {}, [],
     r"deterministic.search_factor = -1.5 is not allowed"),
    ("practice_str", S("deterministic", "practice = 'yes'"), {}, [],
     r"deterministic.practice = 'yes' is not allowed: " + BOOL),
    ("practice_spec_off", S("deterministic", "practice_spec = {life_required_h = 3e4}"), {}, [],
     r"deterministic.practice_spec is not allowed with practice = false"),
    ("practice_spec_neg", S("deterministic", "practice = true\npractice_spec = "
                            "{life_required_h = -1.0}"), {}, [],
     r"deterministic.practice_spec.life_required_h = -1.0 is not allowed"),
    ("practice_check_bad", S("deterministic", "practice = true\npractice_spec = "
                             "{checks = ['speed']}"), {}, [],
     r"deterministic.practice_spec.checks\[\] = 'speed' is not allowed: must be one of"),
    ("practice_bearing_bad", S("deterministic", "practice = true\npractice_spec = "
                               "{front_bearing = 'nose'}"), {}, [],
     r"deterministic.practice_spec: .*nose"),
    ("practice_key", S("deterministic", "practice = true\npractice_spec = {lifetime = 3.0}"),
     {}, [], r"unknown key deterministic.practice_spec.lifetime"),
    ("speeds_removed", S("deterministic", "operating_speeds_rpm = [20000.0]"), {}, [],
     r"unknown key deterministic.operating_speeds_rpm; allowed"),
    ("omega_zero", S("deterministic", "omega_max_rpm = 0.0"), {}, [],
     r"deterministic.omega_max_rpm = 0.0 is not allowed"),
    ("factor_neg", S("deterministic", "factor = -1.2"), {}, [],
     r"deterministic.factor = -1.2 is not allowed"),
    ("det_key", S("deterministic", "stres = true"), {}, [], r"unknown key deterministic.stres"),
    # ------------------------------------------------------------------ [optimization]
    ("p_targets_scalar", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = 0.05"), {}, [],
     r"optimization.p_targets = 0.05 is not allowed: " + ARR),
    ("p_targets_empty", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = []\n"
                             "strategies = []"), {}, [],
     r"optimization.p_targets = \[\] is not allowed with strategies = \[\]"),
    ("p_targets_range", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = [0.1, 1.5]"), {},
     [], r"optimization.p_targets\[1\] = 1.5 is not allowed: must lie in \(0.0, 1.0\)"),
    ("p_targets_dup", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = [0.1, 0.1]"), {},
     [], r"optimization.p_targets = \[0.1, 0.1\] is not allowed: contains duplicates"),
    ("p_targets_pct", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = ['5%']"), {}, [],
     r"optimization.p_targets\[0\] = '5%' is not allowed: " + NUM),
    ("weights_str", S("optimization", "weights = '0.5,0.5'"), {}, [],
     r"optimization.weights = '0.5,0.5' is not allowed: " + ARR),
    ("weights_one", S("optimization", "weights = [1.0]"), {}, [],
     r"optimization.weights = \[1.0\] is not allowed: need two weights"),
    ("weights_zero", S("optimization", "weights = [0.5, 0.0]"), {}, [],
     r"optimization.weights\[1\] = 0.0 is not allowed"),
    ("strategies_str", S("optimization", "strategies = 'rdo'"), {}, [],
     r"optimization.strategies = 'rdo' is not allowed: " + ARR),
    ("strategies_bad", S("optimization", "strategies = ['rdo', 'robust']"), {}, [],
     r"optimization.strategies\[1\] = 'robust' is not allowed: must be one of"),
    ("strategies_dup", S("optimization", "strategies = ['rdo', 'rdo']"), {}, [],
     r"optimization.strategies = \['rdo', 'rdo'\] is not allowed: contains duplicates"),
    ("estimator_bad", S("optimization", "estimator = 'mcmc'"), {}, [],
     r"optimization.estimator = 'mcmc' is not allowed: must be one of"),
    ("optimizer_bad", S("optimization", "optimizer = 'cmaes'"), {}, [],
     r"optimization.optimizer = 'cmaes' is not allowed: must be one of \['nsga2', 'optuna'"),
    ("optimizer_options_key", S("optimization", "optimizer_options = {crossover = 0.9}"), {},
     [], r"optimization.optimizer_options has unknown key\(s\) \['crossover'\] for optimizer "
         r"'nsga2'; allowed"),
    ("optimizer_options_value", S("optimization", "optimizer_options = {crossover_prob = 2.0}"),
     {}, [], r"optimization.optimizer_options.crossover_prob = 2.0 is not allowed"),
    ("optimizer_options_clash", S("optimization", "optimizer_options = {pop_size = 4}"), {},
     [], r"optimization.optimizer_options.pop_size is not allowed: set it in \[optimization\]"),
    ("n_gen_zero", _sub(STUDY, "n_gen = 3", "n_gen = 0"), {}, [],
     r"optimization.n_gen = 0 is not allowed"),
    ("pop_float", _sub(STUDY, "pop_size = 8", "pop_size = 8.5"), {}, [],
     r"optimization.pop_size = 8.5 is not allowed: " + INT),
    ("n_theta_huge", _sub(STUDY, "n_theta = 40", "n_theta = 100000000000"), {}, [],
     r"optimization.pop_size × n_theta = 8 × 100000000000 is not allowed: .* GB of memory"),
    ("eliminate_str", S("optimization", "eliminate_duplicates = 'true'"), {}, [],
     r"optimization.eliminate_duplicates = 'true' is not allowed: " + BOOL),
    ("opt_key", S("optimization", "generations = 3"), {}, [],
     r"unknown key optimization.generations"),
    ("quantile_n_small", S("optimization", "reliability_measure = 'quantile'\n"
                           "pf_bound = 'upper'"), {}, [],
     r"optimization.n_theta = 40 is not allowed with reliability_measure = 'quantile', "
     r"pf_bound = 'upper' and P_target = 0.05"),
    ("measure_bad", S("optimization", "reliability_measure = 'cdf'"), {}, [],
     r"optimization.reliability_measure = 'cdf' is not allowed: must be one of"),
    ("pf_bound_bad", S("optimization", "pf_bound = 'lower'"), {}, [],
     r"optimization.pf_bound = 'lower' is not allowed: must be one of"),
    ("pf_bound_form", S("optimization", "pf_bound = 'upper'\nestimator = 'form'"), {}, [],
     r"optimization.pf_bound = 'upper' is not allowed with estimator = 'form'"),
    ("quantile_is", S("optimization", "reliability_measure = 'quantile'\nestimator = 'is'"),
     {}, [], r"optimization.reliability_measure = 'quantile' is not allowed with estimator"),
    ("estimator_options_str", S("optimization", "estimator_options = 'fast'"), {}, [],
     r"optimization.estimator_options = 'fast' is not allowed: " + TAB),
    # the estimator is built at parse time: a bad option is refused before any work (F12-1)
    ("estimator_options_value", S("optimization", "estimator = 'subset'\n"
                                  "estimator_options = { target_cov = -1 }"), {}, [],
     r"optimization.estimator_options.target_cov = -1 is not allowed: must be a finite number"),
    ("estimator_options_key", S("optimization", "estimator = 'form'\n"
                                "estimator_options = { beta_maxx = 5 }"), {}, [],
     r"optimization.estimator_options has unknown key\(s\) \['beta_maxx'\] for estimator "
     r"'form'; allowed: \[.*'beta_max'"),
    ("estimator_options_mc_key", S("optimization", "estimator_options = { n = 5 }"), {}, [],
     r"optimization.estimator_options has unknown key\(s\) \['n'\] for estimator 'mc'"),
    ("estimator_options_type", S("optimization", "estimator = 'subset'\n"
                                 "estimator_options = { target_cov = 'low' }"), {}, [],
     r"optimization.estimator_options.target_cov = 'low' is not allowed"),
    ("loop_estimator_options", E("optimization", "estimator = 'subset'\n"
                                 "estimator_options = { target_cov = 0 }"), {}, [],
     r"optimization.estimator_options.target_cov = 0 is not allowed"),
    ("slsqp_fronts", S("optimization", "optimizer = 'slsqp'"), {}, [],
     r"optimization.optimizer = 'slsqp' is not allowed with the rbrdo runs: it minimises one"),
    ("slsqp_staircase", S("optimization", "single_objective_optimizer = 'slsqp'"), {}, [],
     r"optimization.single_objective_optimizer = 'slsqp' is not allowed with "
     r"reliability_measure = 'probability'"),
    ("so_optimizer_bad", S("optimization", "single_objective_optimizer = 'bfgs'"), {}, [],
     r"optimization.single_objective_optimizer = 'bfgs' is not allowed: must be one of"),
    ("so_options_key", S("optimization", "single_objective_optimizer = 'slsqp'\n"
                         "reliability_measure = 'quantile'\nsingle_objective_options = "
                         "{n_start = 3}"), {}, [],
     r"optimization.single_objective_options has unknown key\(s\) \['n_start'\]"),
    ("so_options_value", S("optimization", "single_objective_optimizer = 'slsqp'\n"
                           "reliability_measure = 'quantile'\nsingle_objective_options = "
                           "{maxiter = 0}"), {}, [],
     r"optimization.single_objective_options.maxiter = 0 is not allowed"),
    # ------------------------------------------------------------------ [verification]
    ("ver_n_theta_float", _sub(STUDY, "n_theta = 6", "n_theta = 1e11"), {}, [],
     r"verification.n_theta = 100000000000.0 is not allowed: " + INT),
    ("ver_n_theta_huge", _sub(STUDY, "n_theta = 6", "n_theta = 100000000000"), {}, [],
     r"verification.n_theta = 100000000000 is not allowed: .* GB of memory"),
    ("pf_method_bad", S("verification", "pf_method = 'form'"), {}, [],
     r"verification.pf_method = 'form' is not allowed: must be one of \['mc', 'is'\]"),
    ("chunk_zero", S("verification", "chunk = 0"), {}, [],
     r"verification.chunk = 0 is not allowed"),
    ("campbell_one", S("verification", "campbell_speeds = 1"), {}, [],
     r"verification.campbell_speeds = 1 is not allowed: 0 \(no check\) or >= 2"),
    ("campbell_neg", S("verification", "campbell_speeds = -4"), {}, [],
     r"verification.campbell_speeds = -4 is not allowed"),
    ("ver_key", S("verification", "n_thetas = 3"), {}, [],
     r"unknown key verification.n_thetas; allowed"),
    # ------------------------------------------------------------------ [report] (study)
    ("study_baseline_outside", S("report", "baseline = [2000.0, 900.0, 65.0]"), {}, [],
     r"report.baseline: design span_mm = 900.0 is not allowed"),
    ("study_baseline_str", S("report", "baseline = 'default'"), {}, [],
     r"report.baseline = 'default' is not allowed: " + ARR),
    ("study_n_speeds_huge", _sub(STUDY, "n_speeds = 20", "n_speeds = 1000000000000"), {}, [],
     r"report.n_speeds = 1000000000000 is not allowed: .* GB of memory"),
    # ------------------------------------------------------------------ [refine]
    ("refine_neg", S("refine", "rounds = -1"), {}, [], r"refine.rounds = -1 is not allowed"),
    ("refine_theta", S("refine", "rounds = 1\ntheta = 1"), {}, [],
     r"refine.theta = 1 is not allowed"),
    ("refine_hyper", S("refine", "hyper = 'fixed'"), {}, [],
     r"refine.hyper = 'fixed' is not allowed"),
    ("refine_key", S("refine", "round = 1"), {}, [], r"unknown key refine.round"),
    ("refine_substructure", S("surrogate", "structure = 'substructure'") + "[refine]\nrounds = "
     "1\n", {}, [], r"refine.rounds = 1 is not allowed with surrogate.structure = "
                    r"'substructure'"),
    # ------------------------------------------------------------------ surrogate_validation
    ("val_n_test", _sub(VALIDATION, "n_test = 10", "n_test = 1"), {}, [],
     r"validation.n_test = 1 is not allowed"),
    ("val_rel_tol", V("validation", "rel_tol = 0.0"), {}, [],
     r"validation.rel_tol = 0.0 is not allowed"),
    ("val_designs_empty", _sub(VALIDATION, "a = [2000.0, 330.0, 75.0]\n", ""), {}, [],
     r"validation.designs = \{\} is not allowed|validation: designs = \{\} is not allowed"),
    ("val_design_outside", _sub(VALIDATION, "a = [2000.0, 330.0, 75.0]",
                                "a = [2000.0, 30.0, 75.0]"), {}, [],
     r"validation.designs.a: design span_mm = 30.0 is not allowed"),
    ("val_variants_str", V("validation", "variants = 'all'"), {}, [],
     r"validation.variants = 'all' is not allowed: must be a (valid dictionary|table)"),
    ("val_variant_main", VALIDATION + "[validation.variants.main]\nn_doe = 20\n", {}, [],
     r"variants.main is not allowed"),
    ("val_variant_fe", VALIDATION + "[validation.variants.x]\nstructure = 'fe'\n", {}, [],
     r"validation.variants.x.structure = 'fe' is not allowed here"),
    ("val_main_fe", _sub(VALIDATION, "n_doe = 14\nn_jobs = 1", "structure = 'fe'"), {}, [],
     r"surrogate.structure = 'fe' is not allowed here"),
    ("val_variant_bad", VALIDATION + "[validation.variants.x]\nal_n_start = 0\n", {}, [],
     r"validation.variants.x.al_n_start = 0 is not allowed"),
    ("val_variant_key", VALIDATION + "[validation.variants.x]\nn_doee = 3\n", {}, [],
     r"unknown key validation.variants.x.n_doee"),
    ("val_key", V("validation", "n_tests = 3"), {}, [], r"unknown key validation.n_tests"),
    ("val_n_theta_huge", _sub(VALIDATION, "n_theta = 20", "n_theta = 100000000000"), {}, [],
     r"validation.n_theta = 100000000000 is not allowed: .* GB of memory"),
    # ------------------------------------------------------------------ [rig] (kind rig)
    ("rig_scalar", "rig = 3\n" + RIG.split("[rig.campaign]")[0], {}, [],
     r"rig = 3 is not allowed: " + TAB),
    ("rig_key", G("rig", "colour = 1"), {}, [],
     r"unknown key rig.colour; allowed: \['campaign', 'design', 'effects', 'figures', "
     r"'n_jobs', 'sensors', 'variability'\]"),
    ("rig_n_jobs", G("rig", "n_jobs = 0"), {}, [],
     r"rig.n_jobs = 0 is not allowed: must be an integer >= 1"),
    ("rig_effects_str", G("rig", "effects = 'none'"), {}, [],
     r"rig.effects = 'none' is not allowed: must be an array of tables"),
    ("rig_effects_item", G("rig", "effects = [3]"), {}, [],
     r"rig.effects\[0\] = 3 is not allowed: " + TAB),
    ("rig_effect_unknown", G("rig", "effects = [{name = 'warp'}]"), {}, [],
     r"rig.effects\[0\]: name = 'warp' is not allowed: unknown effect 'warp'; known: "
     r".*tool_interface"),
    ("rig_effect_param", G("rig", "effects = [{name = 'anisotropy', q = 1}]"), {}, [],
     r"rig.effects\[0\]: unknown key \S*q; allowed: \['bearings', 's'\]"),
    ("rig_effect_value", G("rig", "effects = [{name = 'anisotropy', s = 'big'}]"), {}, [],
     r"rig.effects\[0\]: .*s = 'big' is not allowed"),
    ("rig_unstable", G("rig", "effects = [{name = 'cross_coupling', kappa = 0.3}]"), {}, [],
     r"rig.effects = \[.*\] is not allowed: the truth is unstable at .* rpm"),
    ("rig_design_short", G("rig", "design = [2000.0, 500.0]"), {}, [],
     r"rig.design = \[2000.0, 500.0\] is not allowed: must be an array of 3 numbers"),
    ("rig_design_str", G("rig", "design = 'baseline'"), {}, [],
     r"rig.design = 'baseline' is not allowed: " + ARR),
    ("rig_design_outside", G("rig", "design = [2000.0, 900.0, 65.0]"), {}, [],
     r"rig.design span_mm = 900.0 is not allowed: must lie in \[300.0, 750.0\]"),
    ("rig_figures_str", G("rig", "figures = 'yes'"), {}, [],
     r"rig.figures = 'yes' is not allowed: " + BOOL),
    ("rig_var_key", G("rig.variability", "bearing_cov = 0.1"), {}, [],
     r"unknown key rig.variability.bearing_cov; allowed: \['balance_grade_mm_s', "),
    ("rig_var_cov_big", G("rig.variability", "bearing_k_cov = 2.0"), {}, [],
     r"rig.variability.bearing_k_cov = 2.0 is not allowed: must lie in \[0.0, 1.0\]"),
    ("rig_var_cov_neg", G("rig.variability", "thermal_preload_cov = -0.1"), {}, [],
     r"rig.variability.thermal_preload_cov = -0.1 is not allowed: must lie in"),
    ("rig_var_cov_nan", G("rig.variability", "tool_mass_cov = nan"), {}, [],
     r"rig.variability.tool_mass_cov = nan is not allowed: must be a finite number"),
    ("rig_var_grade_str", G("rig.variability", "balance_grade_mm_s = 'G2.5'"), {}, [],
     r"rig.variability.balance_grade_mm_s = 'G2.5' is not allowed: " + NUM),
    ("rig_var_fraction_order", G("rig.variability", "unbalance_fraction = [1.0, 0.5]"), {},
     [], r"rig.variability.unbalance_fraction = \(1.0, 0.5\) is not allowed: need 0 <= lo"),
    ("rig_var_fraction_len", G("rig.variability", "unbalance_fraction = [0.5]"), {}, [],
     r"rig.variability.unbalance_fraction = \[0.5\] is not allowed: must be an array of 2"),
    ("rig_var_disk_int", G("rig.variability", "tool_disk = 5"), {}, [],
     r"rig.variability.tool_disk = 5 is not allowed: " + STR),
    ("rig_sensors_key", G("rig.sensors", "bogus = 1"), {}, [],
     r"unknown key rig.sensors.bogus; allowed: \['accelerometer', .*'hammer', 'keyphasor'"),
    ("rig_noise_str", G("rig.sensors", "noise = 'no'"), {}, [],
     r"rig.sensors.noise = 'no' is not allowed: " + BOOL),
    ("rig_targets", G("rig.sensors", "targets = ['tip']"), {}, [],
     r"rig.sensors.targets\[\] = 'tip' is not allowed: must be one of \['front', 'rear', "
     r"'tool'\]"),
    ("rig_probe_noise_neg", G("rig.sensors", "probe = { noise_rms_m = -1e-9 }"), {}, [],
     r"rig.sensors.probe.noise_rms_m = -1e-09 is not allowed: must be a finite number >= 0"),
    ("rig_probe_sens_zero", G("rig.sensors", "probe = { sensitivity_V_per_m = 0.0 }"), {}, [],
     r"rig.sensors.probe.sensitivity_V_per_m = 0.0 is not allowed: must be a finite number > 0"),
    ("rig_probe_key", G("rig.sensors", "probe = { noise = 1e-9 }"), {}, [],
     r"unknown key rig.sensors.probe.noise; allowed: \[.*'noise_rms_m'"),
    ("rig_daq_bits_big", G("rig.sensors", "daq = { bits = 40 }"), {}, [],
     r"rig.sensors.daq.bits = 40 is not allowed: at most 31"),
    ("rig_daq_bits_float", G("rig.sensors", "daq = { bits = 12.5 }"), {}, [],
     r"rig.sensors.daq.bits = 12.5 is not allowed: " + INT),
    ("rig_daq_rate_zero", G("rig.sensors", "daq = { sample_rate_hz = 0.0 }"), {}, [],
     r"rig.sensors.daq.sample_rate_hz = 0.0 is not allowed: must be a finite number > 0"),
    ("rig_keyphasor_edge", G("rig.sensors", "keyphasor = { edge_deg = 50.0 }"), {}, [],
     r"rig.sensors.keyphasor.edge_deg = 50.0 is not allowed: must lie in \[0.0, 30.0\]"),
    ("rig_hammer_peak", G("rig.sensors", "hammer = { peak_N = -3.0 }"), {}, [],
     r"rig.sensors.hammer.peak_N = -3.0 is not allowed: must be a finite number > 0"),
    ("rig_campaign_key", G("rig.campaign", "repeat = 3"), {}, [],
     r"unknown key rig.campaign.repeat; allowed: \[.*'repeats'"),
    ("rig_repeats_zero", _sub(RIG, "repeats = 1", "repeats = 0"), {}, [],
     r"rig.campaign.repeats = 0 is not allowed: must be an integer >= 1"),
    ("rig_repeats_float", _sub(RIG, "repeats = 1", "repeats = 2.5"), {}, [],
     r"rig.campaign.repeats = 2.5 is not allowed: " + INT),
    ("rig_speeds_str", _sub(RIG, "speeds_rpm = [6000.0]", "speeds_rpm = 'fast'"), {}, [],
     r"rig.campaign.speeds_rpm = 'fast' is not allowed: must be an array of numbers, e.g. "
     r"\[1.0, 2.0\] or a table \{start, stop, num\}"),
    ("rig_speeds_order", _sub(RIG, "speeds_rpm = [6000.0]", "speeds_rpm = [3000.0, 2000.0]"),
     {}, [], r"rig.campaign.speeds_rpm = \(3000.0, 2000.0\) is not allowed: a strictly "
             r"increasing list"),
    ("rig_speeds_item", _sub(RIG, "speeds_rpm = [6000.0]", "speeds_rpm = [3000.0, 'x']"), {},
     [], r"rig.campaign.speeds_rpm\[1\] = 'x' is not allowed: " + NUM),
    ("rig_grid_missing", _sub(RIG, "speeds_rpm = [6000.0]",
                              "speeds_rpm = { start = 1000.0, stop = 2000.0 }"), {}, [],
     r"rig.campaign.speeds_rpm.num is missing: it is required"),
    ("rig_grid_key", _sub(RIG, "speeds_rpm = [6000.0]",
                          "speeds_rpm = { start = 1e3, stop = 2e3, num = 3, step = 1 }"), {}, [],
     r"unknown key rig.campaign.speeds_rpm.step; allowed: \['num', 'start', 'stop'\]"),
    ("rig_grid_order", _sub(RIG, "speeds_rpm = [6000.0]",
                            "speeds_rpm = { start = 2e3, stop = 1e3, num = 3 }"), {}, [],
     r"rig.campaign.speeds_rpm.stop = 1000.0 is not allowed: must be > start = 2000.0"),
    ("rig_grid_num_float", _sub(RIG, "speeds_rpm = [6000.0]",
                                "speeds_rpm = { start = 1e3, stop = 2e3, num = 2.5 }"), {}, [],
     r"rig.campaign.speeds_rpm.num = 2.5 is not allowed: " + INT),
    ("rig_runup_order", _sub(RIG, "runup = [1000.0, 2000.0, 0.5]",
                             "runup = [2000.0, 1000.0, 0.5]"), {}, [],
     r"rig.campaign.runup = \(2000.0, 1000.0, 0.5\) is not allowed: need 0 < start_rpm"),
    ("rig_runup_len", _sub(RIG, "runup = [1000.0, 2000.0, 0.5]", "runup = [1000.0, 2000.0]"),
     {}, [], r"rig.campaign.runup = \[1000.0, 2000.0\] is not allowed: must be an array of 3"),
    ("rig_rundown_int", G("rig.campaign", "rundown = 1"), {}, [],
     r"rig.campaign.rundown = 1 is not allowed: " + BOOL),
    ("rig_duration_zero", _sub(RIG, "duration_s = 0.1", "duration_s = 0.0"), {}, [],
     r"rig.campaign.duration_s = 0.0 is not allowed: must be a finite number > 0"),
    # records too short or sampled too slowly to analyse, refused at parse (F12-2)
    ("rig_duration_tiny", _sub(RIG, "duration_s = 0.1", "duration_s = 1e-6"), {}, [],
     r"rig.campaign.duration_s = 1e-06 is not allowed: a steady record must hold at least 5 "
     r"revolutions at the lowest speed \(6000 rpm\), i.e. >= 0.05 s"),
    ("rig_duration_short", _sub(RIG, "speeds_rpm = [6000.0]", "speeds_rpm = [600.0, 6000.0]"),
     {}, [], r"rig.campaign.duration_s = 0.1 is not allowed: .* lowest speed \(600 rpm\), i.e."
     r" >= 0.5 s"),
    ("rig_runup_short", _sub(RIG, "runup = [1000.0, 2000.0, 0.5]",
                             "runup = [1000.0, 2000.0, 1e-6]"), {}, [],
     r"rig.campaign.runup = \[1000.0, 2000.0, 1e-06\] is not allowed: "
     r"the ramp from 1000 to 2000 rpm must hold at least 5 revolutions \(duration >= 0.2 s"),
    ("rig_impact_short", _sub(RIG, "impacts_per_direction = 0",
                              "impacts_per_direction = 1\nimpact_duration_s = 1e-6"), {}, [],
     r"rig.campaign.impact_duration_s = 1e-06 is not allowed: at least 0.05 s"),
    ("rig_daq_slow", G("rig.sensors", "daq = { sample_rate_hz = 300.0 }"), {}, [],
     r"rig.sensors.daq.sample_rate_hz = 300 is not allowed: at least 4 samples per revolution "
     r"at the top speed \(6000 rpm\), i.e. >= 400 Hz"),
    ("disc_duration_tiny", _sub(DISC, "duration_s = 0.4", "duration_s = 0.01"), {}, [],
     r"rig.campaign.duration_s = 0.01 is not allowed: .* lowest speed \(1000 rpm\)"),
    ("loop_duration_tiny", E("rig.campaign", "duration_s = 0.001"), {}, [],
     r"rig.campaign.duration_s = 0.001 is not allowed: a steady record must hold"),
    ("rv_duration_tiny", W("validation", "duration_s = 1e-6"), {}, [],
     r"validation.duration_s = 1e-06 is not allowed: .* lowest speed \(1000 rpm\)"),
    ("rv_ramp_short", _sub(RIG_VAL, "ramps = 0", "ramps = 1\nramp_s = 1e-4"), {}, [],
     r"validation.ramp_s = 0.0001 is not allowed: the ramp from 1000 to 24000 rpm must hold at "
     r"least 5 revolutions"),
    ("rig_impacts_neg", _sub(RIG, "impacts_per_direction = 0", "impacts_per_direction = -1"),
     {}, [], r"rig.campaign.impacts_per_direction = -1 is not allowed: must be an integer >= 0"),
    ("rig_builds_zero", G("rig.campaign", "builds = 0"), {}, [],
     r"rig.campaign.builds = 0 is not allowed: must be an integer >= 1"),
    ("rig_campaign_sensors", G("rig.campaign", "sensors = { noise = false }"), {}, [],
     r"rig.campaign.sensors is not allowed: the sensors are \[rig.sensors\]"),
    ("rig_memory", _sub(RIG, "duration_s = 0.1", "duration_s = 1e6"), {}, [],
     r"rig.campaign.duration_s = 1000000.0 is not allowed: .* GB of memory, more than"),
    ("rig_disk", _sub(RIG, "repeats = 1", "repeats = 1000000000"), {}, [],
     r"rig.campaign.repeats = 1000000000 is not allowed: 1000000002 records .* GB of disk, "
     r"more than"),
    # ------------------------------------------------------------------ kind validation
    ("rv_designs_none", RIG_VAL.split("[designs]")[0], {}, [],
     r"designs: designs has 0 entries: need a baseline and at least one other design"),
    ("rv_design_one", _sub(RIG_VAL, "b = [3000.0, 350.0, 75.0]\n", ""), {}, [],
     r"designs: designs has 1 entries"),
    ("rv_design_short", _sub(RIG_VAL, "a = [2000.0, 500.0, 65.0]", "a = [2000.0, 500.0]"), {},
     [], r"designs.a = \[2000.0, 500.0\] is not allowed: must be an array of 3 numbers"),
    ("rv_design_str", _sub(RIG_VAL, "a = [2000.0, 500.0, 65.0]", "a = 'baseline'"), {}, [],
     r"designs.a = 'baseline' is not allowed: " + ARR),
    ("rv_design_outside", W("designs", "c = [2000.0, 900.0, 65.0]"), {}, [],
     r"designs.c: design span_mm = 900.0 is not allowed: must lie in"),
    ("rv_design_name", W("designs", "'a b' = [2000.0, 500.0, 65.0]"), {}, [],
     r"designs: design name 'a b' is not allowed: a non-empty name without spaces"),
    ("rv_baseline", W("validation", "baseline = 'z'"), {}, [],
     r"designs: baseline = 'z' is not allowed: one of \['a', 'b'\]"),
    ("rv_key", W("validation", "replications = 20"), {}, [],
     r"unknown key validation.replications; allowed: \[.*'n_replications'"),
    ("rv_n_small", _sub(RIG_VAL, "n_replications = 4", "n_replications = 2"), {}, [],
     r"validation.n_replications = 2 is not allowed: must be an integer >= 4"),
    ("rv_method", W("validation", "method = 'fast'"), {}, [],
     r"validation.method = 'fast' is not allowed: must be one of \['phasors', 'records'\]"),
    ("rv_shared", W("validation", "shared = ['bearing']"), {}, [],
     r"validation.shared\[\] = 'bearing' is not allowed: must be one of \['bearings'"),
    ("rv_speeds_str", W("validation", "speeds_rpm = 'all'"), {}, [],
     r"validation.speeds_rpm = 'all' is not allowed: must be an array of numbers, .* or a "
     r"table"),
    ("rv_speeds_table", W("validation", "speeds_rpm = { start = 1000.0, stop = 2000.0 }"), {},
     [], r"validation.speeds_rpm = \{'start': 1000.0, 'stop': 2000.0\} is not allowed: a "
         r"table needs start, stop and step"),
    ("rv_speeds_order", W("validation", "speeds_rpm = [2000.0, 1000.0]"), {}, [],
     r"validation.speeds_rpm = \(2000.0, 1000.0\) is not allowed: a strictly increasing"),
    ("rv_peak_zoom", W("validation", "peak = { n_zoom = 0 }"), {}, [],
     r"validation.peak.n_zoom = 0 is not allowed: must be an integer >= 1"),
    ("rv_ramps", _sub(RIG_VAL, "ramps = 0", "ramps = 5"), {}, [],
     r"validation.ramps = 5 is not allowed: at most n_replications = 4"),
    ("rv_rated_neg", W("validation", "rated_speed_rpm = -1.0"), {}, [],
     r"validation.rated_speed_rpm = -1.0 is not allowed"),
    ("rv_sensors_here", W("validation", "sensors = { noise = false }"), {}, [],
     r"validation.sensors is not allowed: the sensors are \[rig.sensors\]"),
    ("rv_no_tool_probe", W("rig.sensors", "targets = ['front', 'rear']"), {}, [],
     r"rig.sensors.targets = \['front', 'rear'\] is not allowed: validation measures the "
     r"tool tip"),
    ("rv_rig_campaign", W("rig.campaign", "repeats = 3"), {}, [],
     r"unknown key rig.campaign; allowed: \['effects', 'sensors', 'variability'\]"),
    ("rv_rig_effect", W("rig", "effects = [{name = 'warp'}]"), {}, [],
     r"rig.effects\[0\]: name = 'warp' is not allowed: unknown effect 'warp'"),
    ("rv_unstable", W("rig", "effects = [{name = 'cross_coupling', kappa = 0.3}]"), {}, [],
     r"rig.effects: design 'a': the truth is unstable at"),
    ("rv_model_n", W("model", "n_samples = 5"), {}, [],
     r"model.n_samples = 5 is not allowed: must be an integer >= 10"),
    ("rv_model_compare", W("model", "compare = 'yes'"), {}, [],
     r"model.compare = 'yes' is not allowed: " + BOOL),
    ("rv_spindle_file", W("spindle", "geometry = 'g.toml'"), {"g.toml": GEOMETRY_OK}, [],
     r"spindle.geometry = 'g.toml' is not allowed: the rig's truth is the reference spindle"),
    ("rv_uncertainty", W("uncertainty", "std = [0.05]"), {}, [],
     r"uncertainty.std = \[0.05\] is not allowed: need 2 values"),
    ("rv_table", W("study", "x = 1"), {}, [],
     r"unknown table study; allowed: \['designs', 'model', 'rig', 'spindle', 'uncertainty', "
     r"'validation'\]"),
    ("rv_from_int", "[designs]\nfrom = 3\n" + RIG_VAL.split("[designs]")[0], {}, [],
     r"designs.from = 3 is not allowed: " + STR),
    ("rv_from_not_study", "[designs]\nfrom = '.'\n" + RIG_VAL.split("[designs]")[0], {}, [],
     r"designs.from = '.' is not allowed: not a finished study run folder"),
    ("rv_from_and_points", W("designs", "from = '.'"), {}, [],
     r"unknown key designs.a; allowed with designs.from: \['from', 'names'\]"),
    ("rv_from_with_spindle", "[designs]\nfrom = '.'\n" + RIG_VAL.split("[designs]")[0]
     + "[spindle]\n", {}, [],
     r"\[spindle\] and \[uncertainty\] are not allowed with designs.from"),
    # ------------------------------------------------------------------ end_to_end
    ("e2e_loop_when", E("loop", "discrepancy = 'sometimes'"), {}, [],
     r"loop.discrepancy = 'sometimes' is not allowed: must be one of"),
    ("e2e_loop_designs_dup", E("loop", "designs = ['rbrdo 10%', 'rbrdo 10%']"), {}, [],
     r"loop.designs = \['rbrdo 10%', 'rbrdo 10%'\] is not allowed: a name appears twice"),
    ("e2e_loop_designs_str", E("loop", "designs = 'baseline'"), {}, [],
     r"loop.designs = 'baseline' is not allowed: " + ARR),
    ("e2e_loop_key", E("loop", "design = []"), {}, [],
     r"unknown key loop.design; allowed: \['designs', 'discrepancy', 'reoptimise'\]"),
    ("e2e_rig_design", E("rig", "design = [2000.0, 500.0, 65.0]"), {}, [],
     r"rig.design = \[2000.0, 500.0, 65.0\] is not allowed: the campaign's rotor is"),
    ("e2e_no_trial", _sub(LOOP, "trial_unbalance = [0.0, 5e-5, 0.0]\n", ""), {}, [],
     r"rig.campaign.trial_unbalance = None is not allowed: the identification uses"),
    ("e2e_repeats", _sub(LOOP, "repeats = 6", "repeats = 5"), {}, [],
     r"rig.campaign.repeats = 5 is not allowed: the identification's scatter fit"),
    ("e2e_repeats_disc", _sub(E("identification", "fit_on = 'stiffness'"), "repeats = 6",
                              "repeats = 4"), {}, [],
     r"rig.campaign.repeats = 4 is not allowed with loop.discrepancy = 'on_disagreement'"),
    ("e2e_speeds_disc", _sub(LOOP, "num = 8", "num = 6"), {}, [],
     r"rig.campaign.speeds_rpm has 6 speeds: not allowed with loop.discrepancy"),
    ("e2e_ident_source", E("identification", "source = 'results/rig'"), {}, [],
     r"unknown key identification.source; allowed: \["),
    ("e2e_unc_from", E("uncertainty", "from = 'results/identification/x'"), {}, [],
     r"uncertainty.from = 'results/identification/x' is not allowed: the loop's stiffness"),
    ("e2e_unc_std", E("uncertainty", "std = [0.01, 0.02]"), {}, [],
     r"uncertainty.std = \[0.01, 0.02\] is not allowed: the loop's stiffness block"),
    ("e2e_ident_n_boot", E("identification", "n_boot = 0"), {}, [],
     r"identification.n_boot = 0 is not allowed"),
    ("e2e_ident_fit_on", E("identification", "fit_on = 'mass'"), {}, [],
     r"identification.fit_on = 'mass' is not allowed"),
    ("e2e_delta", _sub(LOOP, "[validation]\ndelta_lim_um = 1.0", "[validation]"), {}, [],
     r"validation.delta_lim_um = 19.5 is not allowed: the study has limit.delta_lim_um = 1.0"),
    ("e2e_range", E("validation", "speed_range_rpm = [2000.0, 24000.0]"), {}, [],
     r"validation.speed_range_rpm = \[2000.0, 24000.0\] is not allowed: the study's y"),
    ("e2e_at_speed", _sub(LOOP, "kind = \"peak_unbalance\"",
                          "kind = \"at_speed\"\nspeed_rpm = 24000.0"), {}, [],
     r"response.kind = 'at_speed' is not allowed: the loop validates the peak"),
    ("e2e_val_sensors", E("validation", "sensors = { noise = false }"), {}, [],
     r"validation.sensors is not allowed: the sensors are \[rig.sensors\]"),
    ("e2e_disc_n_draws", E("discrepancy", "n_draws = 20"), {}, [],
     r"discrepancy.n_draws = 20 is not allowed"),
    ("e2e_disc_key", E("discrepancy", "alpa = 0.01"), {}, [],
     r"discrepancy.*alpa"),
    ("e2e_model_n", E("model", "n_samples = 5"), {}, [],
     r"model.n_samples = 5 is not allowed: must be an integer >= 10"),
    ("e2e_table", E("designs", "a = [570.0, 500.0, 65.0]"), {}, [],
     r"unknown table designs; allowed: \["),
    # ------------------------------------------------------------------ identification
    ("id_no_source", IDENT.replace('source = "."\n', ""), {}, [],
     r"identification.source = '' is not allowed: give the rig campaign run folder"),
    ("id_source_int", IDENT.replace('source = "."', "source = 3"), {}, [],
     r"identification.source = 3 is not allowed: " + STR),
    ("id_source_missing", IDENT.replace('source = "."', 'source = "results/rig/r9"'), {}, [],
     r"identification.source = 'results/rig/r9' is not allowed: no such folder"),
    ("id_source_not_campaign", IDENT, {}, [],
     r"identification.source = '.*' is not allowed: not a campaign \(no dataset.json"),
    ("id_source_latest_none", IDENT.replace('source = "."', 'source = "results/rig/latest"'),
     {}, [], r"identification.source = 'results/rig/latest' is not allowed: 'results/rig' "
     r"holds no complete run"),
    ("id_source_failed_run", IDENT, {"meta.json": '{"status": "failed"}'}, [],
     r"identification.source = '.' is not allowed: the run '.' is 'failed', not complete"),
    ("id_rig_design", IDENT, {"meta.json": '{"status": "complete", "kind": "rig"}',
                              "config.json": '{"rig": {"design": [2500.0, 500.0, 65.0]}}'},
     [], r"spindle.baseline = \[2000.0, 500.0, 65.0\] is not allowed: the rig campaign '.' "
     r"was built at design \[2500.0, 500.0, 65.0\]"),
    ("id_no_trial_runs", IDENT, DS_NO_TRIAL, [],
     r"identification.excitation = 'trial' is not allowed with source = '.*': it has no "
     r"trial-weight runs"),
    ("id_no_steady", IDENT, {**DS_NO_TRIAL, "index.jsonl": DS_NO_TRIAL["index.jsonl"].replace(
        "steady", "impact")}, [], r"identification.source = '.*' is not allowed: the dataset "
     r"has no steady records"),
    ("id_group_label", ID("excitation = 'known'\nunbalance = [[0.0, 1e-5, 0.0]]\n"
                          "group_label = 'tool'"), DS_NO_TRIAL, [],
     r"identification.group_label = 'tool' is not allowed: not a label of every record"),
    ("id_summary_speed", ID("excitation = 'known'\nunbalance = [[0.0, 1e-5, 0.0]]\n"
                            "summary_speed_rpm = 30000.0"), DS_NO_TRIAL, [],
     r"identification.summary_speed_rpm = 30000.0 is not allowed: must lie in the campaign's "
     r"speeds \[6000, 6000\] rpm"),
    ("id_excitation", ID("excitation = 'impulse'"), {}, [],
     r"identification.excitation = 'impulse' is not allowed: must be one of \['trial', "
     r"'known'\]"),
    ("id_known_no_unbalance", ID("excitation = 'known'"), {}, [],
     r"identification.unbalance = None is not allowed with excitation = 'known'"),
    ("id_unbalance_shape", ID("unbalance = [[0.0, 1e-5]]"), {}, [],
     r"identification.unbalance\[0\] = \[0.0, 1e-05\] is not allowed: must be an array of 3"),
    ("id_law", ID("law = 'linear'"), {}, [],
     r"identification.law = 'linear' is not allowed: must be one of \['auto', 'constant', "
     r"'quadratic', 'power', 'cubic'\]"),
    ("id_scatter", ID("scatter = 'pooled'"), {}, [],
     r"identification.scatter = 'pooled' is not allowed: must be one of \['auto', 'physical', "
     r"'total'\]"),
    ("id_study", ID("study = 'anisotropic'"), {}, [],
     r"identification.study = 'anisotropic' is not allowed: must be one of \['isotropic', "
     r"'stiffness'\]"),
    ("id_damping", ID("damping = 'modal'"), {}, [],
     r"identification.damping = 'modal' is not allowed: must be one of \['response', "
     r"'impact'\]"),
    ("id_tool_mass", ID("tool_mass = 'weighed'"), {}, [],
     r"identification.tool_mass = 'weighed' is not allowed: must be one of"),
    ("id_damping_no_impacts", ID("excitation = 'known'\nunbalance = [[0.0, 1e-5, 0.0]]\n"
                                 "damping = 'impact'"), DS_NO_TRIAL, [],
     r"identification.damping = 'impact' is not allowed with source = '.*': it has no impact "
     r"records"),
    ("id_fit_on", ID("fit_on = 'damping'"), {}, [],
     r"identification.fit_on = 'damping' is not allowed: must be one of"),
    ("id_n_boot_neg", IDENT.replace("n_boot = 20", "n_boot = -5"), {}, [],
     r"identification.n_boot = -5 is not allowed: must be an integer >= 20"),
    ("id_n_boot_float", IDENT.replace("n_boot = 20", "n_boot = 50.5"), {}, [],
     r"identification.n_boot = 50.5 is not allowed: " + INT),
    ("id_n_jobs", ID("n_jobs = 0"), {}, [],
     r"identification.n_jobs = 0 is not allowed: must be an integer >= 1"),
    ("id_max_rel_se", ID("max_rel_se = 0.0"), {}, [],
     r"identification.max_rel_se = 0.0 is not allowed: must be a finite number > 0"),
    ("id_bandwidth", ID("probe_bandwidth_hz = -1.0"), {}, [],
     r"identification.probe_bandwidth_hz = -1.0 is not allowed"),
    ("id_gain", ID("gains = { front_x = 'high' }"), {}, [],
     r"identification.gains.front_x = 'high' is not allowed: must be a number"),
    ("id_targets_str", ID("targets = 'front'"), {}, [],
     r"identification.targets = 'front' is not allowed: " + ARR),
    ("id_convergence_speed", ID("convergence_speed_rpm = 0.0"), {}, [],
     r"identification.convergence_speed_rpm = 0.0 is not allowed: must be a finite number > 0"),
    ("id_systematic_neg", IDENT + "[identification.systematic]\ngain_sd = -0.02\n", {}, [],
     r"identification.systematic.gain_sd = -0.02 is not allowed: must be a finite number >= 0"),
    ("id_systematic_key", IDENT + "[identification.systematic]\ngain = 0.02\n", {}, [],
     r"unknown key identification.systematic.gain; allowed:"),
    ("id_tool_disk", IDENT + "[identification.systematic]\ntool_disk = 'arbor'\n", {}, [],
     r"identification.systematic.tool_disk = 'arbor' is not allowed: not a disk of the "
     r"\[spindle\] model"),
    ("id_unknown_key", ID("speeds = [1000.0]"), {}, [],
     r"unknown key identification.speeds; allowed: \["),
    ("id_unknown_table", IDENT + "[rig]\nfigures = false\n", {}, [],
     r"unknown table rig; allowed: \['identification', 'spindle'\]"),
    ("id_spindle_geometry", IDENT + "[spindle]\ngeometry = 'none.toml'\n", {}, [],
     r"spindle.geometry file '.*none.toml' does not exist"),
    ("id_missing_table", "[experiment]\nname = 'i'\nkind = 'identification'\n", {}, [],
     r"identification is missing: it is required"),
    # ------------------------------------------------------------------ [uncertainty] from
    ("from_with_mean", S("uncertainty", "from = 'ident/r1'\nmean = [1.0, 1.0]"), {}, [],
     r"uncertainty.mean = \[1.0, 1.0\] is not allowed with from = 'ident/r1': the identified "
     r"model gives θ's mean and covariance"),
    ("from_with_corr", S("uncertainty", "from = 'ident/r1'\ncorr = [[1.0, 0.1], [0.1, 1.0]]"),
     {}, [], r"uncertainty.corr = \[\[1.0, 0.1\], \[0.1, 1.0\]\] is not allowed with from"),
    ("from_empty", S("uncertainty", "from = ''"), {}, [],
     r"uncertainty.from = '' is not allowed: give an identification run folder"),
    ("from_int", S("uncertainty", "from = 3"), {}, [], r"uncertainty.from = 3 is not allowed: "
     + STR),
    ("from_missing", S("uncertainty", "from = 'results/identification/none'"), {}, [],
     r"uncertainty.from = 'results/identification/none' is not allowed: no such file or "
     r"folder"),
    ("from_not_json", S("uncertainty", "from = 'u.json'"), {"u.json": "not json"}, [],
     r"uncertainty.from = '.*u.json' is not allowed: not JSON"),
    ("from_wrong_format", S("uncertainty", "from = 'u.json'"), {"u.json": '{"names": []}'}, [],
     r"uncertainty.from = 'u.json': .*u.json: format = None, version = None: expected "
     r"'surrogate_rbrdo.identified_uncertainty'"),
    ("from_not_identification", S("uncertainty", "from = '.'"),
     {"meta.json": '{"kind": "study", "status": "complete"}', "uncertainty.json": "{}"}, [],
     r"uncertainty.from = '.' is not allowed: not a complete identification run \(its "
     r"meta.json: kind 'study'"),
    ("from_unfinished", S("uncertainty", "from = '.'"),
     {"meta.json": '{"kind": "identification", "status": "failed"}',
      "uncertainty.json": "{}"}, [], r"uncertainty.from = '.' is not allowed: not a complete "
     r"identification run \(its meta.json: kind 'identification', status 'failed'\)"),
    # ------------------------------------------------------------------ kind discrepancy
    ("disc_key", D("discrepancy", "alpah = 0.01"), {}, [],
     r"unknown key discrepancy.alpah; allowed: \[.*'alpha'"),
    ("disc_alpha", D("discrepancy", "alpha = 0.5"), {}, [],
     r"discrepancy.alpha = 0.5 is not allowed: must lie in \[1e-06, 0.2\]"),
    ("disc_alpha_str", D("discrepancy", "alpha = '0.01'"), {}, [],
     r"discrepancy.alpha = '0.01' is not allowed: " + NUM),
    ("disc_n_draws", _sub(DISC, "n_draws = 100", "n_draws = 10"), {}, [],
     r"discrepancy.n_draws = 10 is not allowed: must be an integer >= 100"),
    ("disc_n_jobs", D("discrepancy", "n_jobs = 0"), {}, [],
     r"discrepancy.n_jobs = 0 is not allowed: must be an integer >= 1"),
    ("disc_library_unknown", D("discrepancy", "library = ['housing', 'warp']"), {}, [],
     r"discrepancy.library\[1\] = 'warp' is not allowed: must be one of \[.*'housing'"),
    ("disc_library_empty", D("discrepancy", "library = []"), {}, [],
     r"discrepancy.library = \[\] is not allowed: give at least one registered effect"),
    ("disc_library_twice", D("discrepancy", "library = ['housing', 'housing']"), {}, [],
     r"discrepancy.library = \['housing', 'housing'\] is not allowed: a name appears twice"),
    ("disc_library_str", D("discrepancy", "library = 'housing'"), {}, [],
     r"discrepancy.library = 'housing' is not allowed: " + ARR),
    ("disc_holdout", D("discrepancy", "holdout_every = 1"), {}, [],
     r"discrepancy.holdout_every = 1 is not allowed: must be an integer >= 2"),
    ("disc_extrapolate", D("discrepancy", "extrapolate_fraction = 0.9"), {}, [],
     r"discrepancy.extrapolate_fraction = 0.9 is not allowed: must lie in \[0.0, 0.5\]"),
    ("disc_max_effects", D("discrepancy", "max_effects = 0"), {}, [],
     r"discrepancy.max_effects = 0 is not allowed: must be an integer >= 1"),
    ("disc_identified", D("discrepancy", "use_identified = 'no'"), {}, [],
     r"discrepancy.use_identified = 'no' is not allowed: " + BOOL),
    ("disc_preset", D("discrepancy", "nuisance = { preset = 'lab' }"), {}, [],
     r"discrepancy.nuisance.preset = 'lab' is not allowed: must be one of \['probe_chain', "
     r"'ideal'\]"),
    ("disc_nuisance_key", D("discrepancy", "nuisance = { gains = 0.1 }"), {}, [],
     r"unknown key discrepancy.nuisance.gains; allowed: \[.*'gain_sd'"),
    ("disc_nuisance_damping", D("discrepancy", "nuisance = { damping = 'all' }"), {}, [],
     r"discrepancy.nuisance.damping = 'all' is not allowed: must be one of \['common', "),
    ("disc_nuisance_theta", D("discrepancy", "nuisance = { theta_bounds = [1.2, 1.5] }"), {},
     [], r"discrepancy.nuisance.theta_bounds\[0\] = 1.2 is not allowed: must lie in"),
    ("disc_nuisance_mass", D("discrepancy", "nuisance = { preset = 'probe_chain', "
                                            "mass_sd = 0.9 }"), {}, [],
     r"discrepancy.nuisance.mass_sd = 0.9 is not allowed: must lie in"),
    ("disc_table", D("study", "x = 1"), {}, [],
     r"unknown table study; allowed: \['data', 'discrepancy', 'rig', 'spindle'\]"),
    ("disc_neither", DISC.split("[rig]")[0], {}, [],
     r"\[rig\] or \[data\] is missing: give \[rig\] .* or \[data\] path"),
    ("disc_both", DISC_DATA + DISC[DISC.index("[rig]"):], {"m/phasors.csv": PHASORS}, [],
     r"\[rig\] and \[data\] are not allowed together"),
    ("disc_rig_design", D("rig", "design = [3000.0, 350.0, 75.0]"), {}, [],
     r"rig.design = \[3000.0, 350.0, 75.0\] is not allowed: the model is spindle.baseline = "
     r"\[2000.0, 500.0, 65.0\]"),
    ("disc_spindle_file", D("spindle", "geometry = 'g.toml'"), {"g.toml": GEOMETRY_OK}, [],
     r"spindle.geometry = 'g.toml' is not allowed: the data come from the virtual rig"),
    ("disc_rig_effect", D("rig", "effects = [{name = 'warp'}]"), {}, [],
     r"rig.effects\[0\]: name = 'warp' is not allowed: unknown effect 'warp'"),
    ("disc_rig_unstable", D("rig", "effects = [{name = 'cross_coupling', kappa = 0.3}]"), {},
     [], r"rig.effects = \[.*\] is not allowed: the truth is unstable at"),
    ("disc_data_path_int", DISC_DATA.replace("path = 'm'", "path = 3"), {}, [],
     r"data.path = 3 is not allowed: " + STR),
    ("disc_data_path_missing", DISC_DATA.replace("path = 'm'\n", ""), {}, [],
     r"data.path is missing: it is required"),
    ("disc_data_key", DISC_DATA.replace("path = 'm'", "path = 'm'\nfolder = 'x'"),
     {"m/phasors.csv": PHASORS}, [], r"unknown key data.folder; allowed: \['path'\]"),
    ("disc_data_nowhere", DISC_DATA, {}, [],
     r"data.path = 'm' is not allowed: '.*m' holds no phasors.csv, no dataset"),
    ("disc_data_not_rig", DISC_DATA, {"m/meta.json": '{"kind": "study", "status": '
                                                     '"complete"}'}, [],
     r"data.path = '.*m' is not allowed: a run folder that is not a finished rig campaign "
     r"\(meta.json: kind 'study'"),
    # ------------------------------------------------------------------ finite but absurd
    # (the unit a field's name carries bounds it, core.magnitudes; unitless factors by range)
    ("absurd_stiffness_mean", S("uncertainty", "mean = [1e300, 1.0]"), {}, [],
     r"uncertainty.mean\[0\] = 1e\+300 is not allowed: a stiffness factor's mean must lie in "
     r"\[0.1, 10.0\]"),
    ("absurd_stiffness_mean_20", S("uncertainty", "mean = [1.0, 20.0]"), {}, [],
     r"uncertainty.mean\[1\] = 20.0 is not allowed: .*must lie in \[0.1, 10.0\]"),
    ("absurd_stiffness_std", S("uncertainty", "distribution = 'lognormal'\nstd = [1e300, 0.05]"),
     {}, [], r"uncertainty.std\[0\] = 1e\+300 is not allowed: must be at most 1 x the mean"),
    ("absurd_thermal_max", PU("uncertainty", "thermal_max = 1e300"), {}, [],
     r"uncertainty.thermal_max = 1e\+300 is not allowed: must lie in \[0.0, 5.0\]"),
    ("absurd_delta_lim", S("limit", "delta_lim_um = 1e300"), {}, [],
     r"limit.delta_lim_um = 1e\+300 is not allowed: must be at most 10000 µm in magnitude"),
    ("absurd_yield", S("deterministic", "yield_strength_pa = 1e300"), {}, [],
     r"deterministic.yield_strength_pa = 1e\+300 is not allowed: must be at most 1e\+12 Pa"),
    ("absurd_resonance_factor", S("deterministic", "factor = 1e300"), {}, [],
     r"deterministic.factor = 1e\+300 is not allowed: must lie in \(0.0, 10.0\)"),
    ("absurd_search_factor", S("deterministic", "search_factor = 1e300"), {}, [],
     r"deterministic.search_factor = 1e\+300 is not allowed: must lie in \[1.0, 10.0\]"),
    ("absurd_omega_max", S("deterministic", "omega_max_rpm = 1e300"), {}, [],
     r"deterministic.omega_max_rpm = 1e\+300 is not allowed: must be at most 1e\+06 rpm"),
    ("absurd_unbalance_speed", PU("uncertainty.unbalance", "speed_rpm = 1e300"), {}, [],
     r"uncertainty.unbalance.speed_rpm = 1e\+300 is not allowed: must be at most 1e\+06 rpm"),
    ("absurd_rel_tol", V("validation", "rel_tol = 1e300"), {}, [],
     r"validation.rel_tol = 1e\+300 is not allowed: must be at most 1"),
    ("absurd_campaign_speed", _sub(RIG, "speeds_rpm = [6000.0]", "speeds_rpm = [6000.0, 1e300]"),
     {}, [], r"rig.campaign.speeds_rpm\[1\] = 1e\+300 is not allowed: must be at most 1e\+06 "
     r"rpm in magnitude"),
    ("absurd_duration", _sub(RIG, "duration_s = 0.1", "duration_s = 1e300"), {}, [],
     r"rig.campaign.duration_s = 1e\+300 is not allowed: must be at most 1e\+06 s"),
    ("absurd_runup", _sub(RIG, "runup = [1000.0, 2000.0, 0.5]", "runup = [1000.0, 1e300, 0.5]"),
     {}, [], r"rig.campaign.runup = .* is not allowed: need 0 < start_rpm < end_rpm <= 1e6"),
    ("absurd_trial_unbalance", G("rig.campaign", "trial_unbalance = [0.0, 1e300, 0.0]"), {},
     [], r"rig.campaign.trial_unbalance = \[0.0, 1e\+300, 0.0\] is not allowed: need "
     r"\(position_mm in \[-1e4, 1e4\], magnitude_kgm in \(0, 1e-2\]"),
    ("absurd_probe_gap", G("rig.sensors.probe", "gap_m = 1e300"), {}, [],
     r"rig.sensors.probe.gap_m = 1e\+300 is not allowed: must be at most 10 m in magnitude"),
    ("absurd_probe_sensitivity", G("rig.sensors.probe", "sensitivity_V_per_m = 1e300"), {}, [],
     r"rig.sensors.probe.sensitivity_V_per_m = 1e\+300 is not allowed: must be at most 1e\+06 "
     r"V/m"),
    ("absurd_gain_sd", G("rig.sensors.probe", "gain_error_sd = 1e300"), {}, [],
     r"rig.sensors.probe.gain_error_sd = 1e\+300 is not allowed: must be at most 1 in "
     r"magnitude \(a relative standard deviation above 100 %\)"),
    ("absurd_balance_grade_rig", G("rig.variability", "balance_grade_mm_s = 1e300"), {}, [],
     r"rig.variability.balance_grade_mm_s = 1e\+300 is not allowed: must be at most 4000 mm/s"),
    ("absurd_unbalance_fraction", G("rig.variability", "unbalance_fraction = [0.5, 1e300]"),
     {}, [], r"rig.variability.unbalance_fraction = \(0.5, 1e\+300\) is not allowed: need 0 <= "
     r"lo <= hi <= 10"),
    ("absurd_counter_clock", G("rig.sensors.keyphasor", "counter_clock_hz = 1e300"), {}, [],
     r"rig.sensors.keyphasor.counter_clock_hz = 1e\+300 is not allowed: must be at most 1e\+09 "
     r"Hz"),
    ("absurd_validation_rated", W("validation", "rated_speed_rpm = 1e300"), {}, [],
     r"validation.rated_speed_rpm = 1e\+300 is not allowed: must be at most 1e\+06 rpm"),
    ("absurd_validation_duration", W("validation", "duration_s = 1e300"), {}, [],
     r"validation.duration_s = 1e\+300 is not allowed: must be at most 1e\+06 s"),
    ("absurd_ident_speed", ID("convergence_speed_rpm = 1e300"), {}, [],
     r"identification.convergence_speed_rpm = 1e\+300 is not allowed: must be at most 1e\+06 "
     r"rpm"),
    ("absurd_geometry_length", _sub(S("spindle", "geometry = 'g.toml'"), "", ""),
     {"g.toml": GEOMETRY_OK.replace("length_mm = 300.0", "length_mm = 1e300")}, [],
     r"geometry.sections\[1\].length_mm = 1e\+300 is not allowed: must be at most 10000 mm"),
    # finite but absurd values with a physical lower or upper bound (F12-3)
    ("delta_lim_tiny", S("limit", "delta_lim_um = 1e-9"), {}, [],
     r"limit.delta_lim_um = 1e-09 is not allowed: must be at least 0.001 µm \(1 nm, below the "
     r"resolution of any displacement probe"),
    ("rv_delta_lim_tiny", W("validation", "delta_lim_um = 1e-4"), {}, [],
     r"validation.delta_lim_um = 0.0001 is not allowed: must be at least 0.001 µm"),
    ("omega_max_low", S("deterministic", "omega_max_rpm = 1.0"), {}, [],
     r"deterministic.omega_max_rpm = 1 is not allowed: must be at least \d+ rpm, the top of the "
     r"response's speed range"),
    ("omega_max_at_speed", S("response", "kind = 'at_speed'\nspeed_rpm = 12000.0")
     .replace("[deterministic]\n", "[deterministic]\nomega_max_rpm = 6000.0\n"), {}, [],
     r"deterministic.omega_max_rpm = 6000 is not allowed: must be at least 12000 rpm"),
    ("rig_speed_over", _sub(RIG, "speeds_rpm = [6000.0]", "speeds_rpm = [6000.0, 9e5]"), {}, [],
     r"rig.campaign.speeds_rpm\[1\] = 900000 is not allowed: must be at most 36000 rpm, 1.5 x "
     r"the spindle's speed_max_rpm = 24000"),
    ("rig_runup_over", _sub(RIG, "runup = [1000.0, 2000.0, 0.5]", "runup = [1000.0, 5e4, 2.0]"),
     {}, [], r"rig.campaign.runup = \[1000.0, 50000.0, 2.0\] is not allowed: end_rpm must be at "
     r"most 36000 rpm"),
    ("disc_speed_over", _sub(DISC, "stop = 24000.0", "stop = 9e5"), {}, [],
     r"rig.campaign.speeds_rpm\[\d+\] = [\d.e+]+ is not allowed: must be at most 36000 rpm"),
    ("loop_speed_over", _sub(LOOP, "stop = 24000.0", "stop = 4e4"), {}, [],
     r"rig.campaign.speeds_rpm\[7\] = 40000 is not allowed: must be at most 36000 rpm"),
    ("p_target_half", S("optimization", "strategy_p_target = 0.5"), {}, [],
     r"optimization.strategy_p_target = 0.5 is not allowed: must be below 0.5 \(a failure "
     r"target of 50 % or more is β_t <= 0"),
    ("p_targets_high", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = [0.1, 0.7]"), {},
     [], r"optimization.p_targets\[1\] = 0.7 is not allowed: must be below 0.5"),
    ("n_jobs_huge", _sub(STUDY, "n_gen = 3\nn_jobs = 1", "n_gen = 3\nn_jobs = 1000"), {}, [],
     r"optimization.n_jobs = 1000 is not allowed: must be at most \d+ worker processes \(4 x "
     r"the \d+ cores here, at least 8\)"),
    ("n_jobs_huge_verification", _sub(STUDY, "n_theta = 6\nn_jobs = 1", "n_theta = 6\n"
                                      "n_jobs = 100000"), {}, [],
     r"verification.n_jobs = 100000 is not allowed: must be at most \d+ worker processes"),
    ("n_jobs_huge_ident", ID("n_jobs = 5000"), DS_NO_TRIAL, [],
     r"identification.n_jobs = 5000 is not allowed: must be at most \d+ worker processes"),
    # ------------------------------------------------------------------ the command line
    ("cli_seed_neg", SPINDLE, {}, ["--seed", "-1"], r"--seed = -1 is not allowed"),
    ("cli_seed_dup", SPINDLE, {}, ["--seed", "5", "5"], r"--seed 5 5 is not allowed"),
    ("cli_run_id_escape", SPINDLE, {}, ["--run-id", "../../etc"],
     r"--run-id = '../../etc' is not allowed"),
    ("cli_run_id_abs", SPINDLE, {}, ["--run-id", "/tmp/x"], r"--run-id = '/tmp/x' is not"),
    ("cli_resume_no_id", SPINDLE, {}, ["--resume"], r"--resume is not allowed without"),
    ("cli_resume_missing", SPINDLE, {}, ["--resume", "--run-id", "none"],
     r"--resume: there is no run folder"),
]
