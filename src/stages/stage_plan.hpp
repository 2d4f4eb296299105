// Stages are data (docs/model.md §2): a stage has a start event, phases, and an end.
// The held-stack deployment of bay m (stage j = n - m): driven frame m starts at 0 (m = n) or at
// y_r - l_{m+1} (its bay already open to that height), phase `open` until the pin meets the rail
// (rail entry, an impact), phase `on_rail` until x = 0 (the latch). Retraction is the exact
// reverse, bays 1..n: unlock (an impact), on_rail until the pin leaves the rail where it entered
// (the lower frame lands on the stack), open until frame m is back where its deployment began;
// the last one ends with frame n landing on the stack.
#pragma once
#include <string>
#include <vector>

#include "model/params.hpp"
#include "model/rail.hpp"
#include "stages/phase.hpp"

namespace truss::stages {

enum class StageStart { from_rest_or_kick, continue_motion, unlock };
enum class PhaseEnd { rail_entry, lock, rail_exit, reach_height };

struct PhaseSpec {
  PhaseKind kind = PhaseKind::open;
  double q_start = 0;               // y_m (open) or x (on_rail) at phase start
  double q_end = 0;                 // ... at the phase's end event
  PhaseEnd end = PhaseEnd::rail_entry;
  double lower_held_height_m = 0;   // open: frame m-1; on_rail: frame m-2
};

struct StageSpec {
  int bay = 0;                      // bay m; driven frame m
  double direction = 1.0;           // +1 deploy, -1 retract
  StageStart start = StageStart::continue_motion;
  std::vector<PhaseSpec> phases;
  bool final_landing = false;       // retraction: frame n lands on the stack at the end
  double locked_mass_kg = 0;        // rigid mass above frame m (locked bays and tip)
  double panel_height_offset_m = 0; // H = y_m + offset
  // Rail-entry geometry of this bay (held lower frame at 0).
  double entry_hinge_x_m = 0, entry_upper_height_m = 0;
  // Free stack (docs/model.md §2 "free"): the frames below the driven one are free; the phases' q
  // values are not used (the state lives in free_stack/free_stack.hpp) and entry happens where the
  // motion takes the pin to the rail.
  bool free_stack = false;
  bool contacts = false;            // free stack: unilateral stack contacts D_i >= 0 (docs/model.md §2)
  bool start_kick = true;           // free stack, start from rest in velocity mode: the free frames
                                    // take the kick (else they stay at rest; sim::StackStart)
};

// The rail's geometry, checked once for both stack modes (docs/model-notes.md, "Rail geometry"):
// the entry of each bay m's pin with its lower frame at the stowed height 0 (entries[m], 1..n),
// well posed (away from the straight and the closed bay) and above where the lock of bay m+1
// leaves frame m. Returns an empty string, or "rail geometry: ..." naming the keys, the reason
// and the valid range of rail.x_m.
std::string find_rail_entries(const model::MastParams& mast, std::vector<model::HeldRailEntry>& entries);

// Builds the stages of a held-stack run. Returns an empty string, or "key: reason" if the
// geometry makes the held stack impossible (rail never met, next bay already past the rail).
std::string plan_held_stages(const model::MastParams& mast, double direction, std::vector<StageSpec>& out);

// Builds the stages of a free-stack run: deployment, bays n..1, each phase A until rail entry and
// phase B until the lock; retraction, the held stack's retraction stages run with free frames.
// The rail geometry must be one the held stack runs (find_rail_entries): returns its message
// otherwise.
std::string plan_free_stages(const model::MastParams& mast, double direction, bool contacts, bool start_kick,
                             std::vector<StageSpec>& out);

}  // namespace truss::stages
