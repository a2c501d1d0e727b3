import os
import tempfile
from pathlib import Path

# One BLAS thread a process, as the command sets it (verify/cli/__init__.py), here before numpy loads (the
# xdist workers and the commands tests start inherit it): in-process tests then compute as `garant` does, and
# BLAS threads on these small matrices only competed with the other worker (whole suite 189 s -> 161 s).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")

import numpy as np
import pytest

#: Where things are, for every test: the repository, the tests' data and stands, and the real recordings of
#: ../shared beside the clone.
TESTS = Path(__file__).resolve().parent
ROOT = TESTS.parent
DATA = TESTS / "data"
STANDS = DATA / "stands"
REAL = ROOT.parent / "shared" / "data" / "real"
G_REAL = 9.81744                 # the g the recordings' authors used (shared/data/real/README.md), m/s^2
# Skipped on a machine without shared/, never in CI (CI=true): there the data must be present.
needs_real = pytest.mark.skipif(not REAL.is_dir() and not os.environ.get("CI"),
                                reason="../shared/data/real is not present")

# Derived descriptions are cached (verify/models.py); the tests keep theirs apart from the user's, in a
# folder made once by the process that starts the run (the workers inherit it) and removed at its end.
_OWN_CACHE = None
if "GARANT_CACHE" not in os.environ:
    _OWN_CACHE = os.environ["GARANT_CACHE"] = tempfile.mkdtemp(prefix="garant-test-cache-")

from garant.generated import two_axis as two_axis  # noqa: E402  (after the cache is set)


@pytest.fixture(scope="session")
def mod():
    return two_axis


def C(n, x):
    """The independent oracle of the rotation chains (numpy, written apart from garant): the passive rotation
    by x about the unit vector n, cos x E + (1 - cos x) n n^T - sin x [n x] (C1-C3 of section 2 of 000;
    Rodrigues for a tilted axis)."""
    n = np.asarray(n, float) / np.linalg.norm(n)
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    return np.cos(x) * np.eye(3) + (1 - np.cos(x)) * np.outer(n, n) - np.sin(x) * K


def simulate(mod, positions_deg, physical, sigma, g=9.81, seed=0):
    """Readings (N, 3) in m/s^2 from the exact model plus noise bounded by sigma (units of g)."""
    P = np.deg2rad(np.asarray(positions_deg, float))
    f = mod.readings(P[:, 0], P[:, 1], physical, g).T
    rng = np.random.default_rng(seed)
    return f + g * rng.uniform(-sigma, sigma, f.shape)


def write_csv(path, positions_deg, f, extra=None):
    with open(path, "w") as fh:
        cols = ["alpha_deg", "beta_deg", "f1", "f2", "f3"] + list(extra or {})
        fh.write(",".join(cols) + "\n")
        for k, ((a, b), row) in enumerate(zip(positions_deg, f)):
            cells = [repr(float(a)), repr(float(b))] + [repr(float(v)) for v in row]
            cells += [str(v[k]) for v in (extra or {}).values()]
            fh.write(",".join(cells) + "\n")
    return path


#: Tests that take over a second each on one core (measured with --durations=0): `pytest -m "not slow"` is the
#: fast lane a change is tried with first; CI runs every test.
SLOW = {
    "test_report.py::test_a_batch_summary_page_renders_in_headless_chromium",
    "test_batch.py::test_a_batch_calibrates_each_log_judges_it_and_reports_a_bad_one_on_its_line",
    "test_wedges_axes_detents.py::test_diagnose_advises_only_reachable_positions",
    "test_api.py::test_diagnose_of_the_api_is_the_command",
    "test_api.py::test_every_result_has_a_status_and_its_message",
    "test_api.py::test_plan_of_the_api_is_the_plan_of_the_command",
    "test_arithmetic.py::test_field_arithmetic_is_that_of_the_reals",
    "test_description_cache.py::test_a_planted_entry_is_never_run_and_is_replaced",
    "test_calibrate_norm.py::test_k_batch_is_the_student_t_point",
    "test_calibrate_norm.py::test_noise_rule_holds_on_split_halves_of_every_real_log",
    "test_calibrate_norm.py::test_real_log_bounds_are_the_information_sets",
    "test_calibrate_norm.py::test_real_recordings_calibrate",
    "test_calibration_files.py::test_every_stand_ends_in_a_calibration_that_apply_carries_out",
    "test_calibration_files.py::test_reports_for_estimate_and_calibrate_norm",
    "test_certificates.py::test_committed_certificates_are_what_the_builder_builds",
    "test_certificates.py::test_continuum_solver_matches_the_proven_optima",
    "test_certificates.py::test_every_certificate_in_verify_holds",
    "test_certificates.py::test_example_stands_fully_certified",
    "test_chain.py::test_a_stand_error_past_its_bound_names_the_parameter_and_a_wider_bound_passes",
    "test_chain.py::test_an_assumed_g_is_said_on_its_own_line_by_estimate_and_calibrate_norm",
    "test_chain.py::test_every_effects_extended_model_estimates_and_bounds_the_truth",
    "test_chain.py::test_next_at_done_says_the_verdict_and_the_command_that_calibrates",
    "test_cli.py::test_garant_verify_console_script",
    "test_codegen.py::test_check_command_reports_drift",
    "test_codegen.py::test_headers_and_no_timestamps",
    "test_codegen.py::test_no_drift",
    "test_codegen.py::test_python_m_derive_check_passes",
    "test_diagnose.py::test_an_encoder_harmonic_near_the_floor_is_named_for_a_mems_size_unit",
    "test_diagnose.py::test_clean_sets_raise_no_alarm_whatever_the_unit",
    "test_diagnose.py::test_cli_simulate_and_diagnose",
    "test_diagnose.py::test_diagnose_described_stands",
    "test_diagnose.py::test_hidden_effect_is_named",
    "test_diagnose.py::test_two_effects_at_two_sigma_are_named_and_no_third",
    "test_diagnose.py::test_two_effects_at_two_sigma_both_named",
    "test_diagnose.py::test_two_hidden_effects_both_named",
    "test_described_stands.py::test_derive_plan_simulate_estimate_diagnose",
    "test_described_stands.py::test_two_axis_plans_on_finer_grids_are_the_quarter_turn_plans",
    "test_guarantee.py::test_data_that_refute_sigma_get_a_verdict_not_bounds",
    "test_guarantee.py::test_interpolating_for_many_positions_keeps_the_guaranteed_errors_of_position_by_position",
    "test_guarantee.py::test_no_false_alarms_on_clean_data",
    "test_hostile_inputs.py::test_a_box_certificate_relabelled_as_the_plan_candidates_is_rejected",
    "test_hostile_inputs.py::test_a_plan_search_beyond_its_budget_keeps_its_plan_with_a_proven_floor",
    "test_hostile_inputs.py::test_a_table_with_120_degree_detents_derives_plans_and_certifies",
    "test_hostile_inputs.py::test_certificates_of_a_stand_outside_the_exact_field_are_refused_before_the_search",
    "test_hostile_inputs.py::test_string_in_a_description_cannot_run_code",
    "test_hostile_outputs.py::test_next_draws_its_plot_when_done",
    "test_hostile_outputs.py::test_plan_norm_draws_its_plot_and_refuses_a_route",
    "test_identifiability.py::test_detents_that_see_the_whole_circle_give_the_rank_of_every_reachable_position",
    "test_layout.py::test_wheel_installs_only_the_garant_namespace",
    "test_next.py::test_a_session_for_the_block_parameters_reaches_their_targets",
    "test_next.py::test_a_session_reaches_the_optimal_errors_in_the_fewest_positions",
    "test_next.py::test_data_that_refute_sigma_stop_the_session",
    "test_next.py::test_done_means_estimate_prints_every_bound_at_its_target",
    "test_norm_001.py::test_norm_checks_pass",
    "test_norm_001.py::test_sigma_expansion_is_H_q_to_first_order",
    "test_premises.py::test_a_unit_outside_its_premises_is_named_and_inside_them_is_sound",
    "test_premises.py::test_an_estimate_that_contradicts_the_premises_says_so_instead_of_a_block",
    "test_premises.py::test_mems_blocks_on_ten_sets_are_bounded_within_ten_sigma",
    "test_premises.py::test_mems_unit_bounds_contain_the_truth_and_stay_useful",
    "test_premises.py::test_remainder_part_per_q_against_the_worst_nonlinear_error_found",
    "test_premises.py::test_smallest_supported_sigma_to_its_stated_tolerance",
    "test_readme.py::test_the_first_calibration_runs_as_pasted_after_the_set_up_line",
    "test_remount.py::test_substitutions_26_27_hold_for_every_mounting",
    "test_repeatability.py::test_calibrate_norm_every_imu_of_the_stream",
    "test_repeatability.py::test_fixture_stand_with_known_directions",
    "test_repeatability.py::test_repeatability_names_the_effect_that_was_planted",
    "test_repeatability.py::test_repeatability_on_mimu4444bt_runs_1_to_5",
    "test_repeatability.py::test_the_published_repeatability_tables_are_what_the_command_writes",
    "test_report.py::test_each_report_is_one_self_contained_page",
    "test_report.py::test_each_report_renders_in_headless_chromium",
    "test_report.py::test_next_plots_each_bound_before_and_after",
    "test_report.py::test_the_plan_plot_shows_the_up_direction_of_each_position",
    "test_route.py::test_the_route_of_the_two_axis_plan_is_the_fastest_order",
    "test_rows_can_fail.py::test_norm_plans_red_on_a_plan_missing_a_direction",
    "test_descriptions.py::test_a_description_is_derived_once_and_again_when_it_changes",
    "test_descriptions.py::test_any_identifier_a_user_picks_works",
    "test_descriptions.py::test_builtin_stands_plan",
    "test_descriptions.py::test_description_file_as_model",
    "test_descriptions.py::test_plan_file_travels_to_simulate_and_the_truth_is_saved",
    "test_descriptions.py::test_simulate_estimate_round_trip",
    "test_text.py::test_next_to_every_power_of_ten",
    "test_thermal.py::test_a_chamber_session_that_refutes_a_constant_model_is_told_the_degree_it_needs",
    "test_thermal.py::test_simulate_runs_the_plan_at_each_chamber_temperature",
    "test_thermal.py::test_the_api_takes_a_temperature_degree_as_the_command_does",
    "test_thermal.py::test_the_bound_over_the_range_holds_at_every_temperature_of_it",
    "test_thermal.py::test_the_ardupilot_parameters_correct_the_readings_as_ardupilot_applies_them",
    "test_thermal.py::test_the_px4_parameters_correct_the_readings_as_px4_applies_them",
    "test_thermal.py::test_apply_corrects_each_sample_at_its_own_temperature_within_its_bound",
    "test_thermal.py::test_plan_gives_the_fewest_positions_per_temperature_that_identify_every_coefficient",
    "test_thermal.py::test_too_few_temperatures_for_the_degree_are_refused_naming_what_is_missing",
    "test_information.py::test_96_positions_prove_a_quarter_of_sigma_and_match_an_independent_hull",
    "test_diagnose.py::test_no_effect_no_alarm",
    "test_stand_000.py::test_primal_dual_chebyshev_agree_on_a_coarse_grid",
    "test_text.py::test_up_never_below_and_nearest_within_half_a_unit",
    "test_hostile_outputs.py::test_a_command_that_fails_after_writing_leaves_every_old_file_and_no_new_one",
}


def pytest_collection_modifyitems(items):
    """Mark the tests of SLOW `slow` (every parametrisation of each)."""
    for item in items:
        if f"{item.path.name}::{item.originalname}" in SLOW:
            item.add_marker(pytest.mark.slow)


def pytest_sessionfinish(session):
    """Remove the cache folder this run made (by the process that made it, after every worker is done)."""
    import shutil
    if _OWN_CACHE and not hasattr(session.config, "workerinput"):
        shutil.rmtree(_OWN_CACHE, ignore_errors=True)


def flat(text):
    """Printed text with the command line's wrapping at 100 columns undone: every run of spaces and line breaks as
    one space (a check for a phrase then holds wherever the line was wrapped)."""
    return " ".join(text.split())


def command_line(text, prefix):
    """The command printed on the line that starts with `prefix` (after any indent), its shell continuations (a
    backslash at a line's end) joined: what a user pastes into a shell."""
    lines = text.splitlines()
    k = next(i for i, x in enumerate(lines) if x.strip().startswith(prefix))
    parts = [lines[k].strip()]
    while parts[-1].endswith(" \\"):
        k += 1
        parts[-1] = parts[-1][:-2]
        parts.append(lines[k].strip())
    return " ".join(parts)
