"""The episode core, written once for the single and the vector environment: what happens
between the integrator and Gymnasium, on arrays of rollers (the single environment's are
arrays of one).

============  ====================================================================
module        what it holds
============  ====================================================================
``streams``   counter-based random streams: each draw a pure function of (seed, episode, draw)
``starts``    episode starts (scene, target, start state) with reset's seed and option checks
``record``    the outcome record, declared once: inputs, step quantities, outputs, info keys
``outcome``   the step's outcome for one roller and a block of them (compiled arithmetic)
``kernel``    a task's compiled outcome, alone and fused with the physics; OutcomeKernel
============  ====================================================================
"""

from roller_gym.episode.kernel import (
    Outcome,
    OutcomeKernel,
    TaskKernels,
    flag_table,
    info_rows,
    outcome,
    result_table,
    task_kernels,
)
from roller_gym.episode.record import (
    COMPUTED,
    CONTEXT_FIELDS,
    FLAG_ROWS,
    INFO_KEYS,
    INFO_ROW,
    OUTCOME_ROWS,
    QUANTITIES,
    Step,
    step_record,
)
from roller_gym.episode.starts import (
    CANDIDATES,
    ROUNDS,
    SEED_MAX,
    RestState,
    Starts,
    at_start,
    check_option_names,
    check_seed,
    per_scene_target,
    put,
    reset_mask,
    reset_options,
    scene_rows,
    start_episodes,
    state_option,
    take,
    target_terms,
    vector_seeds,
)
from roller_gym.episode.streams import random_seed, uniform

__all__ = ["CANDIDATES", "COMPUTED", "CONTEXT_FIELDS", "FLAG_ROWS", "INFO_KEYS", "INFO_ROW",
           "OUTCOME_ROWS", "QUANTITIES", "ROUNDS", "SEED_MAX", "Outcome", "OutcomeKernel",
           "RestState", "Starts", "Step", "TaskKernels", "at_start", "check_option_names",
           "check_seed", "flag_table",
           "info_rows", "outcome", "per_scene_target", "put", "random_seed", "reset_mask",
           "reset_options", "result_table", "scene_rows", "start_episodes", "state_option",
           "step_record", "take", "target_terms", "task_kernels", "uniform", "vector_seeds"]
