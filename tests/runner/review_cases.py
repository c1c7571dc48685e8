# ruff: noqa: E501
"""The reviewer's bad inputs of issue 12 (review-runner.md, runner-scripts/bad/cases*.py), as
they were written: ``c(name, config text, files, CLI args, pre)``; ``pre(folder)`` prepares
the folder (a directory or a symbolic link where a file is expected). :data:`PATTERNS` is what
each error must say: the dotted path (or file) and the bad value; the test adds that the line
says what is allowed. Cases that are valid configs (they run) are left out.
"""

from __future__ import annotations

import copy
import json
import os

from surrogate_rbrdo.spindle.reference import reference_spindle

from .bad_inputs import GEOMETRY_OK, SPINDLE, STUDY, VALIDATION, _set, _sub


def S(t, line):
    return _set(STUDY, t, line)


def R(t, line):
    return _set(SPINDLE, t, line)


def V(t, line):
    return _set(VALIDATION, t, line)


GJ = json.dumps({"tool_tip_mm": 0.0,
  "sections": [{"length_mm": 100.0, "outer_diameter_mm": 60.0, "tag": "span"},
               {"length_mm": 300.0, "outer_diameter_mm": 60.0, "tag": "span"}],
  "bearings": [{"name": "front", "position_mm": 100.0, "law": {"type": "constant", "k_N_per_m": 2e8}},
               {"name": "rear", "position_mm": 400.0, "law": {"type": "constant", "k_N_per_m": 2e8}}],
  "unbalances": [{"position_mm": 0.0, "magnitude_kgm": 1e-5}]})


def gj(**repl):
    d = json.loads(GJ)
    d.update(repl)
    return json.dumps(d)


GEO = R("spindle", "geometry = 'g.toml'")
GEOJ = R("spindle", "geometry = 'g.json'")
CASES = []


def c(name, text, files=None, args=(), pre=None):
    CASES.append((name, text, files or {}, list(args), pre))


c("exp_array_of_tables", "[[experiment]]\nname='x'\nkind='study'\n")
c("exp_kind_case", _sub(SPINDLE, 'kind = "spindle_report"', 'kind = "Spindle_Report"'))
c("exp_name_unicode", _sub(SPINDLE, 'name = "r"', 'name = "résumé"'))
c("exp_name_long", _sub(SPINDLE, 'name = "r"', 'name = "' + "a" * 129 + '"'))
c("exp_nested_unknown", R("experiment.extra", "a = 1"))
c("sur_theta_sigmas_nan", S("surrogate", "theta_sigmas = nan"))
c("sur_theta_sigmas_neginf", S("surrogate", "theta_sigmas = -inf"))
c("sur_n_start_neg", S("surrogate", "n_start = -1"))
c("sur_structure_empty", S("surrogate", "structure = ''"))
c("sur_structure_case", S("surrogate", "structure = 'Global'"))
c("sur_nested_table", S("surrogate.extra", "a = 1"))
c("sur_fe_method_bad", _sub(STUDY, "n_doe = 20\nn_jobs = 1\nn_start = 1", "structure = 'fe'\nfe_method = 'magic'"))
c("sur_sub_n_speeds_float", S("surrogate", "structure = 'substructure'\nsub_n_speeds = 12.0"))
c("sur_theta_bounds_nan", S("surrogate", "theta_box = 'bounds'\ntheta_bounds = [nan, 1.5]"))
c("sur_structure_list", S("surrogate", "structure = ['global']"))
c("opt_options_str_value", S("optimization", "optimizer_options = {crossover_prob = '0.9'}"))
c("opt_options_nan", S("optimization", "optimizer_options = {crossover_prob = nan}"))
c("opt_options_scalar", S("optimization", "optimizer_options = 5"))
c("opt_options_bool_for_float", S("optimization", "optimizer_options = {mutation_eta = true}"))
c("opt_options_table_value", S("optimization", "optimizer_options = {mutation_mode = {a = 1}}"))
c("opt_options_mode_bad", S("optimization", "optimizer_options = {mutation_mode = 'sometimes'}"))
c("opt_optuna_bad_key", S("optimization", "optimizer = 'optuna'\noptimizer_options = {engine = 'lean'}"))
c("opt_weights_nan", S("optimization", "weights = [0.5, nan]"))
c("opt_weights_inf", S("optimization", "weights = [inf, 0.5]"))
c("opt_strategy_pt_zero", S("optimization", "strategy_p_target = 0.0"))
c("opt_strategy_pt_str", S("optimization", "strategy_p_target = '5%'"))
c("opt_p_targets_nan", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = [nan]"))
c("opt_p_targets_nested", _sub(STUDY, "p_targets = [0.10, 0.05]", "p_targets = [[0.1]]"))
c("opt_estimator_int", S("optimization", "estimator = 1"))
c("opt_n_jobs_str", S("optimization", "n_jobs = 'all'"))
c("opt_nested_unknown", S("optimization.nsga2", "pop_size = 8"))
c("ver_is_samples_small", S("verification", "pf_method = 'is'\nis_samples = 5"))
c("ver_chunk_str", S("verification", "chunk = '100'"))
c("dm_n_train_huge", _sub(STUDY, "n_train = 10", "n_train = 100000000000"))
c("dm_n_validate_neg", _sub(STUDY, "n_validate = 2", "n_validate = -1"))
c("dm_n_jobs_str", S("design_model", "n_jobs = '2'"))
c("dm_nested", S("design_model.kriging", "a = 1"))
c("refine_tol_nan", S("refine", "rounds = 1\ntol = nan"))
c("refine_designs_zero", S("refine", "rounds = 1\ndesigns = 0"))
c("refine_theta_huge", S("refine", "rounds = 1\ntheta = 100000000000"))
c("resp_speed_inf", S("response", "kind = 'at_speed'\nspeed_rpm = inf"))
c("resp_kind_case", S("response", "kind = 'Peak'"))
c("resp_kind_list", S("response", "kind = ['peak']"))
c("limit_nan", S("limit", "delta_lim_um = nan"))
c("limit_table", S("limit.x", "delta_lim_um = 1.5"))
c("report_baseline_nan", S("report", "baseline = [2000.0, nan, 65.0]"))
c("unc_corr_nan", S("uncertainty", "corr = [[1.0, nan], [nan, 1.0]]"))
c("unc_std_inf", S("uncertainty", "std = [inf, 0.06]"))
c("unc_mean_nested", S("uncertainty", "mean = [[1.0], [1.0]]"))
c("sp_theta_bearings_empty", S("spindle", "theta_bearings = []"))
c("sp_dm_preload_bearing", R("spindle", "design_map = {preload_bearing = 'nose'}"))
c("sp_dm_span_tag", R("spindle", "design_map = {span_tag = 'nope'}"))
c("sp_dm_lower_nan", R("spindle", "design_map = {lower = [1000.0, 300.0, nan]}"))
c("sp_dm_preload_zero", R("spindle", "design_map = {lower = [0.0, 300.0, 50.0]}"))
c("sp_dm_upper_huge", R("spindle", "design_map = {upper = [1e300, 750.0, 80.0]}"))
c("sp_dm_nested_unknown", R("spindle.design_map.extra", "a = 1"))
c("sp_dm_equal_bounds", R("spindle", "design_map = {lower = [2000.0, 300.0, 50.0], upper = [2000.0, 750.0, 80.0]}"))
c("eff_param_str", R("spindle", "effects = [{name = 'speed_softening', a = '0.1'}]"))
c("eff_param_nan", R("spindle", "effects = [{name = 'speed_softening', a = nan}]"))
c("eff_bearings_str", R("spindle", "effects = [{name = 'speed_softening', a = 0.1, bearings = 'front'}]"))
c("eff_bearings_unknown", R("spindle", "effects = [{name = 'speed_softening', a = 0.1, bearings = ['nose']}]"))
c("eff_housing_neg", R("spindle", "effects = [{name = 'housing', k_N_per_m = -1.0}]"))
c("eff_duplicate", R("spindle", "effects = [{name = 'speed_softening', a = 0.1}, {name = 'speed_softening', a = 0.2}]"))
c("eff_param_table", R("spindle", "effects = [{name = 'speed_softening', a = {x = 1}}]"))
c("eff_param_bool", R("spindle", "effects = [{name = 'speed_softening', a = true}]"))
c("eff_delta_inf", R("spindle", "effects = [{name = 'unbalance_error', delta_deg = inf}]"))
c("eff_name_int", R("spindle", "effects = [{name = 5}]"))
c("eff_omega_ref_str", R("spindle", "effects = [{name = 'thermal_preload', b = 0.1, omega_ref = 'rated'}]"))
c("eff_bearings_int", R("spindle", "effects = [{name = 'speed_softening', a = 0.1, bearings = 3}]"))
c("geo_empty", R("spindle", "geometry = ''"))
c("geo_space", R("spindle", "geometry = 'reference '"))
c("geo_dotdot_missing", R("spindle", "geometry = '../../nothere.toml'"))
c("geo_abs_passwd", R("spindle", "geometry = '/etc/passwd'"))
c("geo_dir", GEO, pre=lambda d: (d / "g.toml").mkdir())
c("geo_symlink_loop", GEO, pre=lambda d: (d / "g.toml").symlink_to(d / "g.toml"))
c("geo_symlink_dangling", GEO, pre=lambda d: (d / "g.toml").symlink_to(d / "nowhere.toml"))
c("geo_latin1", GEO, {"g.toml": GEOMETRY_OK.replace('tag = "span"', 'tag = "spän"', 1).encode("latin-1")})
c("geo_unreadable", GEO, {"g.toml": GEOMETRY_OK}, pre=lambda d: os.chmod(d / "g.toml", 0))
c("gj_geometry_int", GEOJ, {"g.json": '{"geometry": 5}'})
c("gj_null", GEOJ, {"g.json": "null"})
c("gj_empty_obj", GEOJ, {"g.json": "{}"})
c("gj_sections_str", GEOJ, {"g.json": gj(sections="abc")})
c("gj_length_str", GEOJ, {"g.json": GJ.replace('"length_mm": 100.0', '"length_mm": "100"')})
c("gj_length_nan", GEOJ, {"g.json": GJ.replace('"length_mm": 100.0', '"length_mm": NaN')})
c("gj_length_neg", GEOJ, {"g.json": GJ.replace('"length_mm": 100.0', '"length_mm": -100.0')})
c("gj_length_zero", GEOJ, {"g.json": GJ.replace('"length_mm": 100.0', '"length_mm": 0.0')})
c("gj_bearing_outside", GEOJ, {"g.json": GJ.replace('"position_mm": 400.0', '"position_mm": 5000.0')})
c("gj_one_bearing", GEOJ, {"g.json": gj(bearings=[json.loads(GJ)["bearings"][0]])})
c("gj_law_str", GEOJ, {"g.json": GJ.replace('{"type": "constant", "k_N_per_m": 2e8}', '"constant"', 1)})
c("gj_k_str", GEOJ, {"g.json": GJ.replace('"k_N_per_m": 2e8', '"k_N_per_m": "2e8"', 1)})
c("gj_k_neg", GEOJ, {"g.json": GJ.replace('"k_N_per_m": 200000000.0', '"k_N_per_m": -2e8', 1)})
c("gj_bearings_obj", GEOJ, {"g.json": gj(bearings={"front": 1})})
c("gj_unbalance_neg", GEOJ, {"g.json": GJ.replace('"magnitude_kgm": 1e-05', '"magnitude_kgm": -1e-05')})
c("gj_section_list_item", GEOJ, {"g.json": gj(sections=[[100.0, 60.0]])})
c("gj_bearing_name_int", GEOJ, {"g.json": GJ.replace('"name": "rear"', '"name": 7')})
c("gj_bearing_dup_name", GEOJ, {"g.json": GJ.replace('"name": "rear"', '"name": "front"')})
c("gj_bom", GEOJ, {"g.json": "\ufeff" + GJ})
c("gj_diam_inf", GEOJ, {"g.json": GJ.replace('"outer_diameter_mm": 60.0', '"outer_diameter_mm": Infinity', 1)})
c("gt_sections_table", GEO, {"g.toml": GEOMETRY_OK.replace("[[geometry.sections]]\nlength_mm = 100.0", "[geometry.sectionz]\nlength_mm = 100.0", 1)})
c("gt_no_span_tag", GEO, {"g.toml": GEOMETRY_OK.replace('tag = "span"', 'tag = "shaft"')})
c("gt_materials_bad", GEO, {"g.toml": GEOMETRY_OK + "[geometry.materials.steel]\ndensity_kg_m3 = 'heavy'\n"})
c("rep_label_slash", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }", 'designs = { "x/y" = [3000.0, 300.0, 80.0] }'))
c("rep_label_escape", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }", 'designs = { "../../../../escaped_label" = [3000.0, 300.0, 80.0] }'))
c("rep_label_empty", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }", 'designs = { "" = [3000.0, 300.0, 80.0] }'))
c("rep_campbell_huge", _sub(SPINDLE, "campbell_speeds = 3", "campbell_speeds = 1000000000000"))
c("rep_n_modes_huge", _sub(SPINDLE, "n_modes = 2", "n_modes = 100000000"))
c("rep_n_campbell_zero", R("report", "n_campbell = 0"))
c("rep_design_nested", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }", "designs = { a = { F = 3000.0 } }"))
c("val_design_nan", _sub(VALIDATION, "a = [2000.0, 330.0, 75.0]", "a = [2000.0, 330.0, nan]"))
c("val_variant_structure_bad", VALIDATION + "[validation.variants.x]\nstructure = 'nope'\n")
c("val_variant_scalar", V("validation", "variants = { x = 5 }"))
c("val_variant_nested", VALIDATION + "[validation.variants.x.extra]\na = 1\n")
c("val_variant_escape", VALIDATION + '[validation.variants."../../../../escaped_variant"]\nn_doe = 14\n')
c("val_n_test_huge", _sub(VALIDATION, "n_test = 10", "n_test = 1000000000000"))
c("val_n_theta_nc_zero", V("validation", "n_theta_nc = 0"))
c("val_rel_tol_nan", V("validation", "rel_tol = nan"))
c("val_variant_bool", V("validation", "variants = { x = { active_learning = 'yes' } }"))
c("cli_run_id_empty", SPINDLE, args=["--run-id", ""])
c("cli_run_id_space", SPINDLE, args=["--run-id", "a b"])
c("cli_run_id_unicode", SPINDLE, args=["--run-id", "ü"])
c("cli_run_id_dash", SPINDLE, args=["--run-id=-x"])
c("cli_run_id_long", SPINDLE, args=["--run-id", "a" * 200])
c("cli_results_is_file", SPINDLE, args=["--results", "exp.toml"])
c("cli_config_dir", SPINDLE, pre=lambda d: ((d / "exp.toml").unlink(), (d / "exp.toml").mkdir()))
REF = reference_spindle().geometry.to_dict()
def rg(f):
    d = copy.deepcopy(REF)
    f(d)
    return json.dumps(d)
def setb(i, k, v):
    def f(d): d["bearings"][i][k] = v
    return f
def setlaw(i, k, v):
    def f(d): d["bearings"][i]["law"][k] = v
    return f
def sets(i, k, v):
    def f(d): d["sections"][i][k] = v
    return f
def top(k, v):
    def f(d): d[k] = v
    return f
c("rg_one_bearing", GEOJ, {"g.json": rg(lambda d: d["bearings"].pop())})
c("rg_no_bearings", GEOJ, {"g.json": rg(lambda d: d.__setitem__("bearings", []))})
c("rg_law_str", GEOJ, {"g.json": rg(setb(1, "law", "preload"))})
c("rg_k_str", GEOJ, {"g.json": rg(setlaw(1, "k_ref_N_per_m", "2.7e8"))})
c("rg_name_int", GEOJ, {"g.json": rg(setb(1, "name", 7))})
c("rg_no_position", GEOJ, {"g.json": rg(lambda d: d["bearings"][1].pop("position_mm"))})
c("rg_elements_huge", GEOJ, {"g.json": rg(sets(1, "elements", 100000000))})
c("rg_elements_zero", GEOJ, {"g.json": rg(sets(1, "elements", 0))})
c("rg_elements_float", GEOJ, {"g.json": rg(sets(1, "elements", 4.5))})
c("rg_speed_inverted", GEOJ, {"g.json": rg(lambda d: (d.__setitem__("speed_min_rpm", 30000.0)))})
c("rg_disk_mass_neg", GEOJ, {"g.json": rg(lambda d: d["disks"][0].__setitem__("mass_kg", -1.0))})
c("rg_material_unknown", GEOJ, {"g.json": rg(sets(1, "material", "titanium"))})
c("rg_max_elem_tiny", GEOJ, {"g.json": rg(top("max_element_length_mm", 1e-6))})
c("rg_rayleigh_nan", GEOJ, {"g.json": rg(top("rayleigh_alpha_per_s", float("nan")))})
c("rg_inner_gt_outer", GEOJ, {"g.json": rg(sets(0, "inner_diameter_mm", 90.0))})
c("rg_exponent_neg", GEOJ, {"g.json": rg(setlaw(0, "exponent", -1.0))})
c("rg_bearing_extra", GEOJ, {"g.json": rg(setb(0, "colour", "red"))})
c("rg_unb_phase_str", GEOJ, {"g.json": rg(lambda d: d["unbalances"][0].__setitem__("phase_deg", "90"))})
c("rg_geometry_wrapped_list", GEOJ, {"g.json": json.dumps({"geometry": [REF]})})
c("sur_n_start_neg2", _sub(STUDY, "n_start = 1", "n_start = -1"))
c("opt_n_jobs_str2", _sub(STUDY, "n_jobs = 1\n[verification]", "n_jobs = 'all'\n[verification]"))
c("grade_huge", R("spindle", "balance_grade_mm_s = 1e300"))
c("sur_al_batch_zero", S("surrogate", "active_learning = true\nal_batch_size = 0"))
c("dm_validate_huge", _sub(STUDY, "n_validate = 2", "n_validate = 10000000000"))
c("seed_datetime", R("experiment", "seed = 1979-05-27"))
c("surrogate_array_tables", STUDY.replace("[surrogate]\nn_doe = 20\nn_jobs = 1\nn_start = 1\n", "[[surrogate]]\nn_doe = 20\n"))
c("dotted_key", S("surrogate", '"n_doe.x" = 1'))
c("unicode_key", S("surrogate", "ñ = 1"))
c("other_kind_table", R("surrogate", "n_doe = 20"))
c("cli_results_empty", SPINDLE, args=["--results", ""])
c("rep_designs_many_labels_ws", _sub(SPINDLE, "designs = { a = [3000.0, 300.0, 80.0] }", 'designs = { " " = [3000.0, 300.0, 80.0], "a\\nb" = [2000.0, 400.0, 70.0] }'))
c("delta_lim_zero_int", S("limit", "delta_lim_um = 0"))
c("opt_optimizer_options_list", S("optimization", "optimizer_options = [1, 2]"))
c("opt_n_theta_one", _sub(STUDY, "n_theta = 40", "n_theta = 1"))
c("ver_pf_is_fe_loop", _sub(STUDY, "n_doe = 20\nn_jobs = 1\nn_start = 1", "structure = 'fe'") + "\n[verification.extra]\na=1\n")

# sizes of every kind's size fields, refused before any work (review items 2 and 10)
c("ver_is_samples_huge", S("verification", "pf_method = 'is'\nis_samples = 1000000000000"))
c("study_campbell_huge", _sub(STUDY, "campbell_speeds = 4", "campbell_speeds = 1000000000000"))
c("study_n_modes_huge", _sub(STUDY, "n_modes = 2", "n_modes = 1000000000"))
c("sub_n_speeds_huge", S("surrogate", "structure = 'substructure'\nsub_n_speeds = 100000000"))
c("al_n_initial_huge", S("surrogate", "active_learning = true\nal_n_initial = 10000000000"))
c("al_pool_huge2", S("surrogate", "active_learning = true\nal_pool_designs = 1000000000\nal_pool_theta = 1000000000"))
c("res_band_pool_huge", S("surrogate", "structure = 'resonance'\nres_band_pool = 1000000000000"))
c("pop_gen_huge", _sub(_sub(STUDY, "pop_size = 8", "pop_size = 100000000"), "n_gen = 3", "n_gen = 100000000"))
c("ver_front_n_theta_huge", S("verification", "front_designs = 3\nfront_n_theta = 100000000000"))
c("ver_campbell_huge", S("verification", "campbell_speeds = 1000000000000"))
c("val_n_doe_huge", _sub(VALIDATION, "n_doe = 14", "n_doe = 10000000"))

c("opt_strategies_rbrdo2", S("optimization", "strategies = ['rbrdo']"))  # item 5: failed in the report

c("cli_seed_float", SPINDLE, args=["--seed", "1.5"])
c("cli_resume_overwrite", SPINDLE, args=["--resume", "--overwrite", "--run-id", "x"])
c("cli_seeds_resume", SPINDLE, args=["--seed", "1", "2", "--resume", "--run-id", "x"])
c("cli_accept_without_resume", SPINDLE, args=["--accept-changes"])


PATTERNS = {
    'exp_array_of_tables': r"config 'exp\.toml': missing \[experiment\] table with name and kind",
    'exp_kind_case': r"experiment\.kind = 'Spindle_Report' is not allowed:",
    'exp_name_unicode': r"experiment\.name = 'résumé' is not allowed:",
    'exp_name_long': r"experiment\.name = 'aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa' is not allowed:",
    'exp_nested_unknown': r"unknown key experiment\.extra; allowed: \['description', 'kind', 'name', 'results_",
    'sur_theta_sigmas_nan': r"surrogate\.theta_sigmas = nan is not allowed:",
    'sur_theta_sigmas_neginf': r"surrogate\.theta_sigmas = \-inf is not allowed:",
    'sur_n_start_neg': r"config file 'exp\.toml' is not valid TOML: Cannot overwrite a value \(at line 9, c",
    'sur_structure_empty': r"surrogate\.structure = '' is not allowed:",
    'sur_structure_case': r"surrogate\.structure = 'Global' is not allowed:",
    'sur_nested_table': r"unknown key surrogate\.extra; allowed: \['active_learning', 'al_batch_size', 'al_m",
    'sur_fe_method_bad': r"surrogate\.fe_method = 'magic' is not allowed:",
    'sur_sub_n_speeds_float': r"surrogate\.sub_n_speeds = 12\.0 is not allowed:",
    'sur_theta_bounds_nan': r"surrogate\.theta_bounds\[0\] = nan is not allowed:",
    'sur_structure_list': r"surrogate\.structure = \['global'\] is not allowed:",
    'opt_options_str_value': r"optimization\.optimizer_options\.crossover_prob = '0\.9' is not allowed:",
    'opt_options_nan': r"optimization\.optimizer_options\.crossover_prob = nan is not allowed:",
    'opt_options_scalar': r"optimization\.optimizer_options = 5 is not allowed:",
    'opt_options_bool_for_float': r"optimization\.optimizer_options\.mutation_eta = True is not allowed:",
    'opt_options_table_value': r"optimization\.optimizer_options\.mutation_mode = \{'a': 1\} is not allowed:",
    'opt_options_mode_bad': r"optimization\.optimizer_options\.mutation_mode = 'sometimes' is not allowed:",
    'opt_optuna_bad_key': r"optimization\.optimizer_options has unknown key\(s\) \['engine'\] for optimizer 'optu",
    'opt_weights_nan': r"optimization\.weights\[1\] = nan is not allowed:",
    'opt_weights_inf': r"optimization\.weights\[0\] = inf is not allowed:",
    'opt_strategy_pt_zero': r"optimization\.strategy_p_target = 0\.0 is not allowed:",
    'opt_strategy_pt_str': r"optimization\.strategy_p_target = '5%' is not allowed:",
    'opt_p_targets_nan': r"optimization\.p_targets\[0\] = nan is not allowed:",
    'opt_p_targets_nested': r"optimization\.p_targets\[0\] = \[0\.1\] is not allowed:",
    'opt_estimator_int': r"optimization\.estimator = 1 is not allowed:",
    'opt_n_jobs_str': r"config file 'exp\.toml' is not valid TOML: Cannot overwrite a value \(at line 20, ",
    'opt_nested_unknown': r"unknown key optimization\.nsga2; allowed: \['eliminate_duplicates', 'estimator', '",
    'ver_is_samples_small': r"verification\.is_samples = 5 is not allowed:",
    'ver_chunk_str': r"verification\.chunk = '100' is not allowed:",
    'dm_n_train_huge': r"design_model\.n_train = 100000000000 is not allowed:",
    'dm_n_validate_neg': r"design_model\.n_validate = \-1 is not allowed:",
    'dm_n_jobs_str': r"design_model\.n_jobs = '2' is not allowed:",
    'dm_nested': r"unknown key design_model\.kriging; allowed: \['n_jobs', 'n_train', 'n_validate'\]",
    'refine_tol_nan': r"refine\.tol = nan is not allowed:",
    'refine_designs_zero': r"refine\.designs = 0 is not allowed:",
    'refine_theta_huge': r"refine\.theta = 100000000000 is not allowed:",
    'resp_speed_inf': r"response\.speed_rpm = inf is not allowed:",
    'resp_kind_case': r"response\.kind = 'Peak' is not allowed:",
    'resp_kind_list': r"response\.kind = \['peak'\] is not allowed:",
    'limit_nan': r"limit\.delta_lim_um = nan is not allowed:",
    'limit_table': r"unknown key limit\.x; allowed: \['delta_lim_um'\]",
    'report_baseline_nan': r"report\.baseline\[1\] = nan is not allowed:",
    'unc_corr_nan': r"uncertainty\.corr\[0\]\[1\] = nan is not allowed:",
    'unc_std_inf': r"uncertainty\.std\[0\] = inf is not allowed:",
    'unc_mean_nested': r"uncertainty\.mean\[0\] = \[1\.0\] is not allowed:",
    'sp_theta_bearings_empty': r"spindle\.theta_bearings = \[\] is not allowed:",
    'sp_dm_preload_bearing': r"spindle\.design_map\.preload_bearing = 'nose' is not allowed:",
    'sp_dm_span_tag': r"spindle\.design_map\.span_tag = 'nope' is not allowed:",
    'sp_dm_lower_nan': r"spindle\.design_map\.lower\[2\] = nan is not allowed:",
    'sp_dm_preload_zero': r"spindle\.design_map: design bounds for preload_N = \[0\.0, 3000\.0\] are not allowed:",
    'sp_dm_upper_huge': r"spindle\.design_map\.upper\[0\] = 1e\+300 is not allowed:",
    'sp_dm_nested_unknown': r"unknown key spindle\.design_map\.extra; allowed: \['lower', 'preload_bearing', 'spa",
    'sp_dm_equal_bounds': r"spindle\.design_map: design bounds for preload_N = \[2000\.0, 2000\.0\] are not allow",
    'eff_param_str': r"spindle\.effects\[0\]\.a = '0\.1' is not allowed:",
    'eff_param_nan': r"spindle\.effects\[0\]\.a = nan is not allowed:",
    'eff_bearings_str': r"spindle\.effects\[0\]\.bearings = 'front' is not allowed:",
    'eff_bearings_unknown': r"spindle\.effects\[0\]\.bearings = \['nose'\] is not allowed:",
    'eff_housing_neg': r"spindle\.effects\[0\]\.k_N_per_m = \-1\.0 is not allowed:",
    'eff_duplicate': r"spindle\.effects\[1\] = 'speed_softening' is not allowed:",
    'eff_param_table': r"spindle\.effects\[0\]\.a = \{'x': 1\} is not allowed:",
    'eff_param_bool': r"spindle\.effects\[0\]\.a = True is not allowed:",
    'eff_delta_inf': r"spindle\.effects\[0\]\.delta_deg = inf is not allowed:",
    'eff_name_int': r"spindle\.effects\[0\]\.name = 5 is not allowed:",
    'eff_omega_ref_str': r"spindle\.effects\[0\]\.omega_ref = 'rated' is not allowed:",
    'eff_bearings_int': r"spindle\.effects\[0\]\.bearings = 3 is not allowed:",
    'geo_empty': r"spindle\.geometry = '' is not allowed:",
    'geo_space': r"spindle\.geometry = 'reference ' is not allowed:",
    'geo_dotdot_missing': r"spindle\.geometry file '.*nothere\.toml' does not exist",
    'geo_abs_passwd': r"spindle\.geometry = '/etc/passwd' is not allowed:",
    'geo_dir': r"spindle\.geometry file '.*g\.toml' is a directory: must be a file",
    'geo_symlink_loop': r"spindle\.geometry file '.*g\.toml' does not exist",
    'geo_symlink_dangling': r"spindle\.geometry file '.*g\.toml' does not exist",
    'geo_latin1': r"spindle\.geometry file '.*g\.toml' is not valid TOML: 'utf\-8' codec can't decode b",
    'geo_unreadable': r"spindle\.design_map\.preload_bearing = 'front' is not allowed:",
    'gj_geometry_int': r"spindle\.geometry file '.*g\.json': geometry = 5 is not allowed:",
    'gj_null': r"spindle\.geometry file '.*g\.json': geometry = None is not allowed:",
    'gj_empty_obj': r"spindle\.geometry file '.*g\.json': sections is missing: it is required",
    'gj_sections_str': r"spindle\.geometry file '.*g\.json': sections = 'abc' is not allowed:",
    'gj_length_str': r"spindle\.geometry file '.*g\.json': sections\[0\]\.length_mm = '100' is not allowed:",
    'gj_length_nan': r"spindle\.geometry file '.*g\.json': sections\[0\]\.length_mm = nan is not allowed:",
    'gj_length_neg': r"spindle\.geometry file '.*g\.json': sections\[0\]\.length_mm = \-100\.0 is not allowed:",
    'gj_length_zero': r"spindle\.geometry file '.*g\.json': sections\[0\]\.length_mm = 0\.0 is not allowed:",
    'gj_bearing_outside': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.position_mm = 5000\.0 is not allowed:",
    'gj_one_bearing': r"spindle\.design_map\.preload_bearing = 'front' is not allowed:",
    'gj_law_str': r"spindle\.design_map\.preload_bearing = 'front' is not allowed:",
    'gj_k_str': r"spindle\.design_map\.preload_bearing = 'front' is not allowed:",
    'gj_k_neg': r"spindle\.geometry file '.*g\.json': bearings\[0\]\.law\.k_N_per_m = \-200000000\.0 is not allowed:",
    'gj_bearings_obj': r"spindle\.geometry file '.*g\.json': bearings = \{'front': 1\} is not allowed:",
    'gj_unbalance_neg': r"spindle\.geometry file '.*g\.json': unbalances\[0\]\.magnitude_kgm = \-1e\-05 is not allowed:",
    'gj_section_list_item': r"spindle\.geometry file '.*g\.json': sections\[0\] = \[100\.0, 60\.0\] is not allowed:",
    'gj_bearing_name_int': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.name = 7 is not allowed:",
    'gj_bearing_dup_name': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.name = 'front' is not allowed:",
    'gj_bom': r"spindle\.design_map\.preload_bearing = 'front' is not allowed:",
    'gj_diam_inf': r"spindle\.geometry file '.*g\.json': sections\[0\]\.outer_diameter_mm = inf is not allowed:",
    'gt_sections_table': r"spindle\.geometry file '.*g\.toml': unknown key geometry\.sectionz; allowed: \['bear",
    'gt_no_span_tag': r"spindle\.design_map\.preload_bearing = 'front' is not allowed:",
    'gt_materials_bad': r"spindle\.geometry file '.*g\.toml': unknown key geometry\.materials\.steel\.density_k",
    'rep_label_slash': r"report\.designs = 'x/y' is not allowed:",
    'rep_label_escape': r"report\.designs = '\.\./\.\./\.\./\.\./escaped_label' is not allowed:",
    'rep_label_empty': r"report\.designs = '' is not allowed:",
    'rep_campbell_huge': r"report\.campbell_speeds = 1000000000000 is not allowed:",
    'rep_n_modes_huge': r"report\.n_modes = 100000000 is not allowed:",
    'rep_n_campbell_zero': r"report\.n_campbell = 0 is not allowed:",
    'rep_design_nested': r"report\.designs\.a = \{'F': 3000\.0\} is not allowed:",
    'val_design_nan': r"validation\.designs\.a\[2\] = nan is not allowed:",
    'val_variant_structure_bad': r"validation\.variants\.x\.structure = 'nope' is not allowed:",
    'val_variant_scalar': r"validation\.variants\.x = 5 is not allowed:",
    'val_variant_nested': r"unknown key validation\.variants\.x\.extra; allowed: \['active_learning', 'al_batch_",
    'val_variant_escape': r"validation\.variants = '\.\./\.\./\.\./\.\./escaped_variant' is not allowed:",
    'val_n_test_huge': r"validation\.n_test = 1000000000000 is not allowed:",
    'val_n_theta_nc_zero': r"validation\.n_theta_nc = 0 is not allowed:",
    'val_rel_tol_nan': r"validation\.rel_tol = nan is not allowed:",
    'val_variant_bool': r"validation\.variants\.x\.active_learning = 'yes' is not allowed:",
    'cli_run_id_empty': r"\-\-run\-id = '' is not allowed:",
    'cli_run_id_space': r"\-\-run\-id = 'a b' is not allowed:",
    'cli_run_id_unicode': r"\-\-run\-id = 'ü' is not allowed:",
    'cli_run_id_dash': r"\-\-run\-id = '\-x' is not allowed:",
    'cli_run_id_long': r"\-\-run\-id = 'aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa' is not allowed:",
    'cli_results_is_file': r"\-\-results = 'exp\.toml' is not allowed:",
    'cli_config_dir': r"config file 'exp\.toml' is a directory: must be a file",
    'rg_one_bearing': r"spindle\.theta_bearings = \['front', 'rear'\] is not allowed:",
    'rg_no_bearings': r"spindle\.geometry file '.*g\.json': bearings = \[\] is not allowed:",
    'rg_law_str': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.law = 'preload' is not allowed:",
    'rg_k_str': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.law\.k_ref_N_per_m = '2\.7e8' is not allowed:",
    'rg_name_int': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.name = 7 is not allowed:",
    'rg_no_position': r"spindle\.geometry file '.*g\.json': bearings\[1\]\.position_mm is missing: it is requ",
    'rg_elements_huge': r"spindle\.geometry file '.*g\.json': sections\[1\]\.elements = 100000000 is not allowed:",
    'rg_elements_zero': r"spindle\.geometry file '.*g\.json': sections\[1\]\.elements = 0 is not allowed:",
    'rg_elements_float': r"spindle\.geometry file '.*g\.json': sections\[1\]\.elements = 4\.5 is not allowed:",
    'rg_speed_inverted': r"spindle\.geometry file '.*g\.json': speed_max_rpm = 24000\.0 is not allowed:",
    'rg_disk_mass_neg': r"spindle\.geometry file '.*g\.json': disks\[0\]\.mass_kg = \-1\.0 is not allowed:",
    'rg_material_unknown': r"spindle\.geometry file '.*g\.json': sections\[1\]\.material = 'titanium' is not allowed:",
    'rg_max_elem_tiny': r"spindle\.geometry file '.*g\.json': max_element_length_mm = 1e\-06 is not allowed:",
    'rg_rayleigh_nan': r"spindle\.geometry file '.*g\.json': rayleigh_alpha_per_s = nan is not allowed:",
    'rg_inner_gt_outer': r"spindle\.geometry file '.*g\.json': sections\[0\]\.inner_diameter_mm = 90\.0 is not allowed:",
    'rg_exponent_neg': r"spindle\.geometry file '.*g\.json': bearings\[0\]\.law\.exponent = \-1\.0 is not allowed:",
    'rg_bearing_extra': r"spindle\.geometry file '.*g\.json': unknown key bearings\[0\]\.colour; allowed: \['law",
    'rg_unb_phase_str': r"spindle\.geometry file '.*g\.json': unbalances\[0\]\.phase_deg = '90' is not allowed:",
    'rg_geometry_wrapped_list': r"spindle\.geometry file '.*g\.json': geometry = \[\{'sections': \[\{'length_mm': 100\.0, 'outer_diameter_mm': \.\.\. is not allowed:",
    'sur_n_start_neg2': r"surrogate\.n_start = \-1 is not allowed:",
    'opt_n_jobs_str2': r"optimization\.n_jobs = 'all' is not allowed:",
    'grade_huge': r"spindle\.balance_grade_mm_s = 1e\+300 is not allowed:",
    'sur_al_batch_zero': r"surrogate\.al_batch_size = 0 is not allowed:",
    'dm_validate_huge': r"design_model\.n_validate = 10000000000 is not allowed:",
    'seed_datetime': r"experiment\.seed = '1979\-05\-27' is not allowed:",
    'surrogate_array_tables': r"surrogate = \[\{'n_doe': 20\}\] is not allowed:",
    'dotted_key': r"unknown key surrogate\.n_doe\.x; allowed: \['active_learning', 'al_batch_size', 'al",
    'unicode_key': r"config file 'exp\.toml' is not valid TOML: Invalid statement \(at line 6, column 1",
    'other_kind_table': r"unknown table surrogate; allowed: \['report', 'spindle'\]",
    'cli_results_empty': r"\-\-results = '' is not allowed:",
    'rep_designs_many_labels_ws': r"report\.designs = ' ' is not allowed:",
    'delta_lim_zero_int': r"limit\.delta_lim_um = 0\.0 is not allowed:",
    'opt_optimizer_options_list': r"optimization\.optimizer_options = \[1, 2\] is not allowed:",
    'opt_n_theta_one': r"optimization\.n_theta = 1 is not allowed:",
    'ver_pf_is_fe_loop': r"unknown key verification\.extra; allowed: \['campbell_speeds', "
                         r"'chunk', 'front_designs', 'front_n_theta', 'is_samples', 'n_jobs', 'n_th",
    'cli_seed_float': r"argument --seed: invalid int value: '1\.5'",
    'cli_resume_overwrite': r"argument --overwrite: not allowed with argument --resume",
    'cli_seeds_resume': r"--resume: there is no run folder '.*x-seed1' to continue",
    'cli_accept_without_resume': r"--accept-changes is not allowed: it needs --resume",
    'ver_is_samples_huge': r"verification\.is_samples = 1000000000000 is not allowed: .* GB",
    'study_campbell_huge': r"report\.campbell_speeds = 1000000000000 is not allowed: .* GB",
    'study_n_modes_huge': r"report\.n_modes = 1000000000 is not allowed: the model has \d+ modes",
    'sub_n_speeds_huge': r"surrogate\.sub_n_speeds = 100000000 is not allowed: .* GB",
    'al_n_initial_huge': r"surrogate\.al_n_initial = 10000000000 is not allowed: .* GB",
    'al_pool_huge2': r"surrogate\.al_pool_designs × al_pool_theta = 1000000000 × 1000000000 is "
                     r"not allowed: .* GB",
    'res_band_pool_huge': r"surrogate\.res_band_pool = 1000000000000 is not allowed: .* GB",
    'pop_gen_huge': r"optimization\.pop_size × n_gen = 100000000 × 100000000 is not allowed: "
                    r"the arrays they size need .* GB",
    'ver_front_n_theta_huge': r"verification\.front_n_theta = 100000000000 is not allowed: .* GB",
    'ver_campbell_huge': r"verification\.campbell_speeds = 1000000000000 is not allowed: .* GB",
    'val_n_doe_huge': r"surrogate\.n_doe = 10000000 is not allowed: .* GB",
    'opt_strategies_rbrdo2': r"optimization\.strategies\[0\] = 'rbrdo' is not allowed: the RBRDO "
                             r"runs are set by p_targets",
}
