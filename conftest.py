"""Fixtures shared by every test tree: where the paper's reference scenarios
live (metamodel/examples/scenarios, a copy of the project's shared/scenarios
kept inside the repository so that no test reads outside it), and the test tiers."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings

# Property tests check values, not timings: hypothesis's 200 ms deadline per example
# failed them on a loaded shared machine ("Unreliable test timings").
settings.register_profile("modd", deadline=None)
settings.load_profile("modd")

REPO = Path(__file__).resolve().parent
SCENARIOS = REPO / "metamodel" / "examples" / "scenarios"


@pytest.fixture(scope="session")
def scenarios_dir() -> Path:
    if not SCENARIOS.is_dir():
        pytest.fail(f"the reference scenarios are missing: {SCENARIOS}")
    return SCENARIOS


@pytest.fixture(scope="session")
def expected(scenarios_dir: Path) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((scenarios_dir / "expected.json").read_text())
    return data


# -- Tiers ---------------------------------------------------------------------
# ``make check`` runs the unit tests of every component: ``-m "not e2e and not
# slow"``. A test is ``e2e`` when it starts other processes (the CLI, servers,
# the PubBroker, a compiler) or a network server: everything under tests/ and
# the component tests named here (a module, or module::test). ``make test``
# runs them all. Marking here rather than in each file keeps one list to read.
CROSS_PROCESS = (
    "tests/",
    "metamodel/tests/test_cli.py",
    "metamodel/tests/test_wire_contract.py::test_a_fake_value_reaches_both_codecs_and_validation",
    "metamodel/tests/test_collector.py::test_convert_to_collector_cli",
    "metamodel/tests/test_collector.py::test_validate_with_encoding_option",
    "metamodel/tests/plan/test_plan_json.py::test_plan_does_not_depend_on_the_hash_seed",
    "generators/tests/test_cpp_driver_e2e.py",
    "generators/tests/test_hostile_strings.py",
    "generators/tests/test_regenerate.py",
    "generators/tests/test_packaged.py",
    "runtime/python/tests/test_radio.py",
    "backend/tests/test_app.py",
    "backend/tests/test_archives.py",
    "backend/tests/test_archive_export.py",
    "backend/tests/test_archive_bounds.py",  # the archive worker processes
    "backend/tests/test_archive_pool.py",
    "backend/tests/test_frontend.py",
    "backend/tests/test_hardening.py",
    "backend/tests/test_live.py",
    "backend/tests/test_dedup.py::test_two_stations_windows_reach_the_browser_once",  # zenoh
    "backend/tests/test_dedup.py::test_without_the_hubs_memory_the_browser_gets_them_twice",
    "backend/tests/test_plan_guard.py",  # the planner's process pool
    "backend/tests/test_postgres.py",
    "backend/tests/test_push.py",
    "backend/tests/test_relay.py",
    "backend/tests/test_restore.py::test_restore_into_a_new_directory_is_private",  # the CLI
    "backend/tests/test_restore.py::test_a_hostile_postgresql_dump_runs_nothing",  # PostgreSQL
    "backend/tests/test_scene_proxy.py::test_scene_in_a_browser_under_its_csp",  # Chromium
    "backend/tests/test_schemathesis.py",
    "backend/tests/test_store.py",
)


# Unit tests that take several seconds (property tests, solver oracles, races):
# ``slow``, so run by ``make test`` but not by ``make check``.
SLOW = (
    "metamodel/tests/test_roundtrip_property.py",
    "metamodel/tests/plan/test_buffers_oracle.py",
    "metamodel/tests/test_collector.py::test_any_document_exports_to_what_the_original_form_keeps",
    "metamodel/tests/plan/test_schedule_bounds.py::test_count_matches_the_previous_algorithm",
    "backend/tests/test_saverace.py",
    "backend/tests/test_login_race.py::test_200_concurrent_wrong_logins_from_rotated_addresses",
    "backend/tests/test_login_shared_machine.py::"
    "test_50_wrong_logins_from_a_local_process_do_not_stop_the_admins_right_login",
    "backend/tests/test_json_depth.py::test_depth_matches_the_regex_walk",
    "backend/tests/test_download_growing.py",  # a 24 MiB file grown while downloaded
    "runtime/python/tests/test_archive_recover.py::test_no_input_gives_a_traceback",
    # a 10^6-epoch file (~100 MB) built and read against a time bound
    "runtime/python/tests/test_state_files.py::test_a_million_recorded_configs_are_read_in_bounded_time",
    "backend/tests/test_plan.py::test_scenario1_plan_is_the_planners",
    "backend/tests/test_plan.py::test_scenario2_with_the_milp",
    # a second or more each, none bound by a time (loss simulations, nested documents):
    # make check stays under 2 minutes on 2 cores
    "runtime/python/tests/test_shutdown.py::"
    "test_the_case_is_the_one_that_deadlocks_a_handler_setting_the_event",
    "backend/tests/test_validation_errors.py::test_no_body_makes_an_answer_fail",
    "runtime/python/tests/test_radio_shared.py::"
    "test_two_stations_each_hear_the_drone_with_their_own_loss",
    "runtime/python/tests/test_backfill_loss.py::test_heavy_loss_still_finishes_once_each",
    "runtime/python/tests/test_quantised.py::"
    "test_sum_and_average_derived_from_all_stay_within_half_a_step",
    "backend/tests/test_model_text_depth.py::"
    "test_every_read_of_an_invalid_revision_answers_without_a_500",
    "backend/tests/test_model_text_depth.py::"
    "test_deep_json_model_text_is_a_located_error_on_every_text_route",
    "backend/tests/test_plan_calibrate.py::test_the_live_plan_is_calibrated_by_a_held_archive",
    "runtime/python/tests/test_dataset_received.py::test_subscribers_chosen_and_a_cut_record",
    "backend/tests/test_store_processes.py::test_store_processes_answer_as_the_threads_do",
    "runtime/python/tests/test_archive_recover.py::"
    "test_each_of_25_single_byte_flips_keeps_every_chunk_whose_data_checks",
)


def _listed(node: str, listed: tuple[str, ...]) -> bool:
    return any(node == c or (c.endswith((".py", "/")) and node.startswith(c)) for c in listed)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    for item in items:
        node = item.nodeid.split("[", 1)[0]
        if _listed(node, CROSS_PROCESS):
            item.add_marker(pytest.mark.e2e)
        elif _listed(node, SLOW):
            item.add_marker(pytest.mark.slow)
