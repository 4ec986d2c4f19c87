/* job.h: the job runner shared by the CLI (`frepmill simulate`) and the
 * daemon: program -> motions -> swept volumes -> stock, with progress
 * reports along the way. Both front ends call fm_job_run, so they run
 * exactly the same pipeline (ARCHITECTURE.md, "The layers"). */
#ifndef FM_JOB_H
#define FM_JOB_H

#include <stddef.h>
#include <stdint.h>

#include "check/check.h"
#include "cycle_times.h"
#include "core/core.h"
#include "stock/stock.h"
#include "sweep/motion.h"
#include "tools/tools.h"
#include "toolpaths/gcode/gcode.h"
#include "toolpaths/plan/plan.h"
#include "toolpaths/traj/traj.h"

typedef enum fm_program_kind {
    FM_PROGRAM_AUTO = 0, /* by extension: .json is a trajectory, anything else G-code */
    FM_PROGRAM_GCODE,
    FM_PROGRAM_TRAJECTORY,
    FM_PROGRAM_LIVE      /* motions from a controller (fm_job_spec.source) */
} fm_program_kind;

/* Where a live job's motions come from: the daemon's queue of controller
 * positions (Modbus live mode). next() waits for the next motion and fills
 * *out (kind, start, end, tool, feed, t0, t1, line, index: the source
 * numbers its motions from 0 and times them); it returns 1 for a motion, 0
 * when the source has ended, -1 to stop the job (FM_OK, result.stopped).
 * *more says whether another motion is already waiting: when none is, the
 * runner cuts what it holds and reports progress before asking again, so
 * the stock follows the machine. */
typedef struct fm_job_motion_source {
    void *user;
    int (*next)(void *user, fm_motion *out, int *more);
} fm_job_motion_source;

/* The collision check (lib/check), run in the same pass as the cut
 * (ARCHITECTURE.md, "Checking in the same pass"): every motion is related to the
 * stock as the runner cuts it, and findings are reported as they are
 * found. The check has a grid of its own voxel: the job's own grid when
 * voxel and band agree (`frepmill check`), else a second grid cut batch by
 * batch beside it, so that the findings depend on the check's options and
 * never on the simulation's voxel: `frepmill check`, `frepmill simulate
 * --check` and the daemon give the same findings for the same inputs. */
#define FM_JOB_CHECK_VOXEL 0.5
#define FM_JOB_MAX_FIXTURES 64

typedef struct fm_job_check {
    fm_check_options options;
    double voxel_mm;                             /* 0: FM_JOB_CHECK_VOXEL */
    const char *fixtures[FM_JOB_MAX_FIXTURES];   /* a HyperFun model (.hf) or a closed STL mesh */
    int fixture_count;
} fm_job_check;

void fm_job_check_default(fm_job_check *check);

typedef struct fm_job_spec {
    /* The program: a file, or text held by the caller (then program_name
     * names it in errors). */
    const char *program_path;
    const char *program_text;
    size_t program_length;
    const char *program_name;
    fm_program_kind program_kind;

    /* Stock: "box:X0,Y0,Z0,X1,Y1,Z1", "cylinder:X,Y,Z0,Z1,R", or the path
     * of a .hf, .stl or .vdb file. */
    const char *stock_spec;
    /* Tools: a JSON or LinuxCNC .tbl file, or a table already parsed (then
     * tools_path is only used to resolve relative HyperFun tool files). */
    const char *tools_path;
    const fm_tool_table *tools;

    fm_stock_options stock;   /* voxel size, band, memory budget, threads */
    double rapid_rate;        /* mm/min; 0: 5000 */
    /* Consecutive motions of one tool are cut together while their path
     * length stays under this many tool diameters (0: 1; negative: never
     * batch). Batching changes nothing in the result but the per-block
     * attribution (docs/simulate.md). */
    double batch_diameters;

    /* Design comparison (docs/simulate.md): the intended part, a .stl mesh,
     * a .hf model or a frepmill .vdb snapshot; NULL for none. Deviations up
     * to tolerance_mm (0: half a voxel) count as on the design. */
    const char *design_path;
    double tolerance_mm;
    /* Stop after the motions of this source line (0: run to the end): the
     * job ends at the first motion of another line that follows one of
     * LINE's, or, when LINE makes no motion, at the first motion of a line
     * after it; the stock is then as the program leaves it there. */
    int stop_at_line;

    /* Resuming (the daemon after a restart): start from this stock instead
     * of stock_spec (the job takes ownership, also on error), and cut only
     * the motions from index skip_motions on (the program is still
     * interpreted from the start, so modal state is right). */
    fm_stock *resume_stock;
    long skip_motions;

    /* G-code: "linuxcnc" (NULL: the default) or "fanuc" (docs/gcode.md),
     * the folders of subprogram files (':'-separated), and Fanuc's
     * reference points for G28/G30 (machine mm; all zero: the origin). */
    const char *dialect;
    const char *subroutine_path;
    double reference_points[4][3];
    int calculator_input;     /* Fanuc: X5 is 5 mm, not 0.005 */
    /* The machine's rotary axes (docs/check.md "Machine file"); NULL: 3-axis.
     * The G-code front end turns A B C words into joint values with it. */
    const fm_machine *machine;
    /* The machine's state at the start (docs/check.md "Machine file";
     * fm_job_spec_start_state decides it for every entrance). has_start 1:
     * the tool tip stands at start (machine mm) before the first block, for
     * the interpreter and the check alike (the check's own start is set to
     * it); 0: the interpreter's dialect default and the check's own start.
     * initial_tool: the tool in the spindle before the first M6 (0: none;
     * a motion with no tool cuts with the table's only tool when it has
     * exactly one, and not at all otherwise). */
    int has_start;
    double start[3];
    int initial_tool;
    /* The machine's dynamics (docs/plan.md; the machine file's "dynamics"):
     * the survey plans the program's cycle time as the controller runs it.
     * NULL or not given: the cycle time is the feed-only figure. */
    const fm_plan_machine *dynamics;

    /* The collision check (NULL: none). When resuming, the check's own
     * grid is cut from the start, the motions before skip_motions
     * included, so that its findings are those of a run from the start. */
    const fm_job_check *check;

    /* Live mode (program_kind FM_PROGRAM_LIVE): the motions' source. */
    const fm_job_motion_source *source;

    /* The swept volumes' search budget per point (fm_sweep_options.
     * max_evaluations; 0: the default 20,000). Smaller budgets are for
     * tests that provoke the budget warning (fm_job_result.voxels_uncertain). */
    size_t sweep_evaluations;

    /* Where the program's motions are kept (fm_job_motions_replay_file
     * serves them after the job: the daemon's toolpath); NULL: in memory,
     * spilled to a temporary file beyond a budget. The program is
     * interpreted once per job either way, its motions replayed for the cut
     * and the blame; again only when a motion cannot be kept (a
     * trajectory's parametric path: then no file is left) or the cut's
     * probe must read the stock (G38). */
    const char *motion_log;
} fm_job_spec;

void fm_job_spec_default(fm_job_spec *spec);

/* A snapshot of where the job is, for progress bars and status endpoints. */
typedef struct fm_job_progress {
    long motions_done;
    long motions_total;
    double program_time;       /* s, end of the last motion cut */
    double program_time_total; /* s */
    /* 1: program_time and program_time_total are the controller's (the
     * machine's dynamics planned them, docs/plan.md); 0: feed-only */
    int time_planned;
    double feed_only_time_total; /* s, the feed-only figure beside */
    int line;                  /* source line of the last motion cut */
    long block;                /* N number of that line, -1 if none */
    int tool;
    double position[3];        /* tool tip at the end of the last motion */
    /* The rotary joints A, B, C at its end (degrees; NAN for an axis the
     * motion's machine does not have) and its spindle speed (rev/min; NAN
     * for a live job, whose moves carry none). */
    double rotary[3];
    double spindle_rpm;
    double removed_mm3;
    double elapsed_s;          /* wall time since the cutting started */
    /* Every motion with an index below this one is in the stock now (the
     * motion that triggered this cut may still be pending in the next
     * batch): a snapshot taken in this callback resumes with skip_motions
     * = resume_from. */
    long resume_from;
    /* The stock after this cut, valid only during the callback, which runs
     * on the job's thread between cuts: the place to snapshot it. */
    fm_stock *stock;
    /* Live jobs: no motion is waiting now (the stock has caught up with
     * the machine): the moment to publish what changed. */
    int idle;
    /* The design when the spec names one (for deviation colours), or NULL;
     * valid during the callback. */
    const fm_design *design;
    /* The budget warning so far (fm_job_result.voxels_uncertain and
     * uncertain_line). */
    size_t voxels_uncertain;
    int uncertain_line;
} fm_job_progress;

typedef struct fm_job_hooks {
    void *user;
    /* Called after each cut (a motion or a batch); non-zero stops the job
     * (FM_ERR_INPUT "cancelled" is not used: the job ends with FM_OK and
     * result.stopped set). */
    int (*progress)(void *user, const fm_job_progress *progress);
    /* Called for every motion as the program produces it, without
     * touching the stock (and so without ending a batch early): for
     * toolpath overlays and logs. A PARAM motion's path is valid during the
     * call. */
    void (*on_motion)(void *user, const fm_motion *motion);
    /* Called as the check opens a finding (index into fm_check_get of
     * check), on the job's thread, before the motion that found it is cut;
     * its depth and extent grow while later motions extend it. */
    void (*on_finding)(void *user, const fm_check *check, size_t index);
    /* Called once, before the first cut, with the stock the job starts
     * from (made, or the snapshot it resumes); it may be read (meshed)
     * during the call, not kept. */
    void (*on_stock)(void *user, fm_stock *stock);
} fm_job_hooks;

#define FM_JOB_TOP_BLOCKS 10
/* Gouge and excess regions a report lists (deepest first). */
#define FM_JOB_MAX_REGIONS 100

/* The motion blamed for a gouge region: the one whose swept volume reaches
 * deepest at the region's deepest point (docs/simulate.md). */
typedef struct fm_job_blame {
    int line; /* source line; 0 when no motion of this program reaches it */
    int tool;
} fm_job_blame;

typedef struct fm_job_result {
    fm_stock *stock;           /* the final stock, owned by the caller (fm_stock_free) */
    double initial_volume_mm3;
    double final_volume_mm3;
    double removed_volume_mm3;
    double surface_area_mm2;
    long motions;
    long blocks;               /* distinct source lines that cut */
    double program_time_s;     /* feed-only: each motion's length over its feed */
    double cycle_time_s;       /* as the controller plans it; program_time_s when not planned */
    int cycle_time_planned;    /* 1: from the machine's dynamics (toolpaths/plan) */
    /* 1: the motions were cut with their planned times (top_blocks' t0/t1,
     * the progress, the stock's history are the controller's) */
    int times_planned;
    /* cycle_time_s per tool, operation and block with the feed-only figures
     * beside (has_cycle_times: 0 for live jobs, or when the planner failed) */
    int has_cycle_times;
    fm_cycle_summary cycle_times;
    double wall_time_s;
    size_t peak_memory_bytes;  /* peak resident set of the process */
    double voxel_mm;
    double initial_lo[3], initial_hi[3]; /* bounds of the stock before the first cut, mm (within a voxel) */
    int stopped;               /* a hook stopped the job */
    size_t tool_count;
    fm_stock_tool_volume tools[64];
    /* What the tool table says of each of tools[] (same order), for the
     * report: the description as the library names it, its flutes and
     * presets (feeds and speeds; Fusion 360's start values). */
    struct {
        char description[128];
        int flute_count;
        int preset_count;
        fm_tool_preset presets[FM_TOOL_MAX_PRESETS];
    } tool_info[64];
    size_t top_block_count;
    fm_stock_block top_blocks[FM_JOB_TOP_BLOCKS];
    /* Work of all cuts summed (fm_stock_cut_stats), and how many cuts (a
     * batch of motions is one cut): for benchmarks and profiling. */
    fm_stock_cut_stats cut_stats;
    long cuts;
    /* The budget warning: voxels left possibly under-cut because a swept
     * volume's search ran out of its budget before proving the value there
     * (fm_stock_cut_stats.voxels_uncertain summed over cuts; should be 0),
     * the most they may lack (mm), and the first source line of the first
     * cut (a motion or a batch) that had any (0 when none, or when that
     * motion has no source line). */
    size_t voxels_uncertain;
    double uncertain_max_mm;
    int uncertain_line;
    /* With spec.check: the finished check (its findings closed), owned by
     * the caller (fm_check_free), also when a hook stopped the job; and the
     * wall time its relations took. */
    fm_check *check;
    double check_time_s;
    /* spec.stop_at_line when the job stopped there (it then ends as done,
     * not stopped), else 0. */
    int stopped_at_line;
    /* With a design: the design (for deviation colours; owned by the
     * caller, fm_design_free), the deviation (fm_deviation_free) and the
     * blame of each listed gouge; the time the comparison took (building
     * the design, comparing, blaming), wall and CPU of the process, and
     * its three steps' shares (for bench/design). */
    fm_design *design;
    int has_deviation;
    fm_deviation deviation;
    fm_job_blame gouge_blame[FM_JOB_MAX_REGIONS];
    double design_wall_s, design_cpu_s;
    double design_build_wall_s, design_build_cpu_s;
    double design_compare_wall_s, design_compare_cpu_s;
    double design_blame_wall_s, design_blame_cpu_s;
    /* Material of the final stock thinner than a voxel: counted in the
     * volume, absent from the mesh (fm_stock_thin_material; the thin-wall
     * warning). has_thin is 0 when the search itself failed. */
    int has_thin;
    fm_stock_thin_report thin;
    /* How many times the program was interpreted (1: the survey's motions
     * were replayed for the cut and the blame). */
    int interpretations;
    /* The no-tool warning: feed motions with no tool in the spindle (none
     * given at the start, none loaded by M6, and a table of more than one
     * tool) whose tool tip goes into the stock (fm_check_tip_in_stock):
     * they cut nothing, where the machine would drive its spindle's nose.
     * Their count (0: none) and the first one's source line. */
    int no_tool_line;
    long no_tool_motions;
} fm_job_result;

/* The motions of a job's program, kept (job_motions.c). */
typedef struct fm_job_motions fm_job_motions;
void fm_job_motions_free(fm_job_motions *log);
long fm_job_motions_count(const fm_job_motions *log);
/* The motions in order into sink (a non-zero return stops it, FM_OK);
 * machine: the job's, which the motions' rotary poses read. */
fm_status fm_job_motions_replay(fm_job_motions *log, const fm_machine *machine,
                                fm_motion_sink sink, void *user, fm_error *err);
/* The same from the file a job kept (spec.motion_log), after it or while
 * it cuts: FM_ERR_IO when there is none (interpret the program instead). */
fm_status fm_job_motions_replay_file(const char *path, const fm_machine *machine,
                                     fm_motion_sink sink, void *user, fm_error *err);

/* Free what a result owns (stock, design, deviation, check); safe on a zeroed
 * result. */
void fm_job_result_release(fm_job_result *result);

/* Run the whole job. On success result->stock holds the final stock. On
 * error nothing is left allocated and err says what and where (programs
 * and models: file:line:column); FM_ERR_INPUT is bad input,
 * FM_ERR_LIMIT a budget. hooks may be NULL. */
fm_status fm_job_run(const fm_job_spec *spec, const fm_job_hooks *hooks, fm_job_result *result,
                     fm_error *err);

/* Interpret the spec's program (G-code or trajectory, with its tools and
 * rapid rate) into motions for sink, touching no stock: the toolpath the
 * run cuts. */
fm_status fm_job_interpret(const fm_job_spec *spec, fm_motion_sink sink, void *user,
                           fm_error *err);

/* The one program dispatch, in two steps for callers that need more of
 * the interpreters than a job does (`frepmill motions`: skipping, inch
 * start, block delete, messages): the interpreters' options a spec gives
 * (tools: the table G-code reads tool lengths from, NULL for none), and
 * the spec's program (G-code, or a trajectory by kind or .json extension)
 * run with them. */
fm_status fm_job_program_options(const fm_job_spec *spec, const fm_tool_table *tools,
                                 fm_gcode_options *gcode, fm_traj_options *traj, fm_error *err);
fm_status fm_job_program_run(const fm_job_spec *spec, const fm_gcode_options *gcode,
                             const fm_traj_options *traj, fm_motion_sink sink, void *user,
                             fm_error *err);

/* The tools the program's comments name (--tools-from-program,
 * options.tools_from_program): the spec's G-code interpreted once with no
 * table and no stock, every comment handed to toolpaths/tooltable's reader
 * of CAM posts' tool headers (docs/tooltable.md); warnings (each guessed
 * field) to opt. FM_ERR_INPUT when the program is not G-code or no comment
 * names a tool. */
struct fm_tooltable_options;
fm_status fm_job_tools_from_program(const fm_job_spec *spec,
                                    const struct fm_tooltable_options *opt, fm_tool_table *out,
                                    fm_error *err);

/* The machine's state at the start, decided once for every entrance (the
 * job document, `frepmill motions`): the tool tip at the machine's "start"
 * when it gives one, else at the dialect's power-on place (LinuxCNC the
 * origin, Fanuc the first reference point: spec->dialect and
 * spec->reference_points); the tool in the spindle: initial_tool when above
 * 0 (--initial-tool, options.initial_tool), else the machine's
 * "initial_tool", else none. machine may be NULL. */
void fm_job_spec_start_state(fm_job_spec *spec, const fm_check_machine *machine, int initial_tool);

/* Parse and create the stock of a spec string (also used by `frepmill
 * check`). */
fm_stock *fm_job_make_stock(const char *spec, const fm_stock_options *opt, fm_error *err);

/* The path length the runner batches motions by: the chord, plus for arcs a
 * full circumference per turn (an upper bound). Benchmarks that replay the
 * runner's batching use it too. */
double fm_job_motion_length(const fm_motion *motion);

/* Does path end in ext (".hf", ...), case-insensitively? */
int fm_path_has_extension(const char *path, const char *ext);

/* Peak resident set size of this process in bytes (0 if unknown). */
size_t fm_job_peak_rss(void);

#endif
