# SPDX-License-Identifier: BSD-3-Clause
# Sourced by the benchmark and evaluation scripts: where the two human exploration paths they
# replay (user_1.dat, user_2.dat) come from.
#   afam_trajectories AFAM_EXE DIR
# Sets AFAM_TRAJ_DIR to a folder holding user_1.dat and user_2.dat, and AFAM_TRAJ_KIND to
# "recorded" or "generated", and prints one line saying which:
#   - recorded: $AFAM_TRAJECTORIES, when it names a folder holding both files (the paper's
#     recorded paths carry no licence, so the repository does not ship them);
#   - generated: otherwise, exploration walks written into DIR by `afam trajectory --kind walk`
#     (seed 1 for user_1.dat, 2 for user_2.dat; 400 views each, as the recorded ones).
afam_trajectories() {
  local afam="$1" dir="$2"
  if [ -n "${AFAM_TRAJECTORIES:-}" ] && [ -f "$AFAM_TRAJECTORIES/user_1.dat" ] &&
     [ -f "$AFAM_TRAJECTORIES/user_2.dat" ]; then
    AFAM_TRAJ_DIR="$AFAM_TRAJECTORIES"
    AFAM_TRAJ_KIND=recorded
    echo "trajectories: recorded paths from $AFAM_TRAJ_DIR"
    return 0
  fi
  if [ -n "${AFAM_TRAJECTORIES:-}" ]; then
    echo "trajectories: AFAM_TRAJECTORIES=$AFAM_TRAJECTORIES lacks user_1.dat or user_2.dat" >&2
  fi
  mkdir -p "$dir"
  "$afam" trajectory "$dir/user_1.dat" --kind walk --views 400 --seed 1 --quiet || return 1
  "$afam" trajectory "$dir/user_2.dat" --kind walk --views 400 --seed 2 --quiet || return 1
  AFAM_TRAJ_DIR="$dir"
  AFAM_TRAJ_KIND=generated
  echo "trajectories: GENERATED exploration walks in $dir (afam trajectory, seeds 1 and 2), not" \
       "recorded human paths; set AFAM_TRAJECTORIES to a folder with user_1.dat and user_2.dat for those"
}
