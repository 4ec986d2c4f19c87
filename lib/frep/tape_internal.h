/* tape_internal.h: the compiled tape (a flat list of instructions over
 * register slots) and the evaluator state, shared by tape.c, eval.c,
 * interval.c, grad.c, special.c, relations.c and field.c. Not public. */
#ifndef FM_TAPE_INTERNAL_H
#define FM_TAPE_INTERNAL_H

#include <stdatomic.h>

#include "frep/frep_internal.h"

/* Points per batch chunk: one instruction runs over a whole chunk before the
 * next, so the registers of a chunk (regs * 256 * 8 bytes) stay in cache. */
#define FM_CHUNK 256
/* Nesting of special ops (a projection of a projection ...): each level is a
 * sub-tape with its own evaluator, so the depth is bounded. */
#define FM_TAPE_MAX_DEPTH 16
/* Upper bound on instructions of one tape (and on register slots). */
#define FM_TAPE_MAX_INSNS (1u << 24)

/* Slots 0..3 hold x, y, z, t; then one slot per parameter; then the work
 * registers. Value numbers (SSA ids) use the same numbering for leaves, and
 * nleaf + i for the result of instruction i. */
#define FM_NO_OPERAND UINT32_MAX

enum { FM_IMM_A = 1u, FM_IMM_B = 2u };

typedef struct fm_insn {
    uint8_t op;       /* fm_op; FM_OP_CONST loads imm into out */
    uint8_t imm_mask; /* FM_IMM_A / FM_IMM_B: that operand is imm, not a register */
    uint32_t out, a, b, c; /* register slots */
    uint32_t sa, sb, sc;   /* value numbers of the operands (for shortening) */
    uint32_t aux;          /* special ops: index into the shared special table */
    double imm;
} fm_insn;

typedef struct fm_special {
    uint8_t op;
    uint32_t axis;          /* PROJECT */
    double value, value2;   /* PROJECT lo, hi; BALL_MAX, NORMAL_OFFSET d */
    struct fm_tape *child;  /* the child's sub-tape (NULL for VOXELS) */
    fm_voxel_grid grid;     /* VOXELS: a copy owned here */
} fm_special;

/* What a tape and the tapes shortened from it share: parameter names and the
 * special ops (with their sub-tapes). Reference counted because a shortened
 * tape may outlive the tape it was made from. */
typedef struct fm_tape_shared {
    atomic_int refs;
    size_t nparams;
    char **param_names;
    size_t nspecials;
    fm_special *specials;
    int depth; /* nesting level of this tape (0 at the top) */
} fm_tape_shared;

struct fm_tape {
    fm_tape_shared *shared;
    double *param_values; /* nparams, this tape's own copy */
    uint32_t nleaf;       /* 4 + nparams */
    uint32_t nregs;       /* register slots including leaves */
    uint32_t reg_capacity; /* slots an evaluator needs for this tape and its shortenings */
    size_t ninsns;
    fm_insn *insns;
    uint32_t result;      /* register slot of the result */
    uint32_t result_ssa;  /* value number of the result */
    size_t root_ninsns;   /* length of the tape shortenings start from (sizes scratch) */
    size_t insns_cap;     /* instructions insns has room for (a tape rewritten in place) */
};

struct fm_evaluator {
    const fm_tape *root;
    const fm_tape *tape;
    uint32_t cap;         /* register slots allocated */
    double *reg;          /* cap */
    double *batch;        /* cap * FM_CHUNK */
    fm_interval *ivl;     /* cap: enclosure of the non-NaN values */
    uint8_t *ivl_nan;     /* cap: 1 if the value may be NaN somewhere in the box */
    double *grad;         /* cap * 5: value, d/dx, d/dy, d/dz, d/dt */
    uint8_t *choice;      /* choice_cap: decided branch of each instruction */
    size_t choice_cap;
    size_t nsub;
    struct fm_evaluator **sub; /* one per special op (NULL for VOXELS) */
    /* shortening's scratch (interval.c), kept so that shortening a tape
     * per leaf of a grid allocates nothing: value-number maps (3 per value
     * number), liveness, and the shortened code */
    uint32_t *sh_map;
    uint8_t *sh_live;
    fm_insn *sh_code;
    size_t sh_nvn_cap, sh_code_cap;
};

/* tape.c */
/* Make a tape from a list of instructions in value-number form (operands in
 * sa/sb/sc, imm_mask and imm set), assigning register slots. Takes ownership
 * of insns. Shares `shared` (adds a reference). */
fm_tape *fm_tape_from_ssa(fm_tape_shared *shared, const double *param_values, fm_insn *insns,
                          size_t ninsns, uint32_t result_ssa, size_t root_ninsns);
void fm_tape_shared_release(fm_tape_shared *s);
/* Register slots for insns (value-number form, nleaf leaves): a slot is
 * reused once the last reader of its value has run. scratch holds
 * 3 * (nleaf + ninsns) entries. Fills the slots of insns, sets *result to
 * the result's slot and returns the number of slots. */
uint32_t fm_tape_assign_slots(fm_insn *insns, size_t ninsns, uint32_t nleaf, uint32_t result_ssa,
                              uint32_t *scratch, uint32_t *result);

/* eval.c */
static inline double fm_insn_operand(const double *reg, const fm_insn *in, int which)
{
    if (which == 0) return (in->imm_mask & FM_IMM_A) ? in->imm : reg[in->a];
    if (which == 1) return (in->imm_mask & FM_IMM_B) ? in->imm : reg[in->b];
    return reg[in->c];
}

/* special.c: one special instruction in each mode (VOXELS, whose operands
 * are registers, has its own helpers). */
double fm_special_point(fm_evaluator *ev, const fm_insn *in, const double p[4]);
double fm_voxels_grad(const fm_voxel_grid *grid, double x, double y, double z, double d[3]);
fm_interval fm_voxels_interval(const fm_voxel_grid *grid, const fm_interval xyz[3]);
fm_interval fm_special_interval(fm_evaluator *ev, const fm_insn *in, const fm_interval box[4],
                                int *maybe_nan);
double fm_special_grad(fm_evaluator *ev, const fm_insn *in, const double p[4], double grad[4]);

/* interval.c: interval evaluation that also says whether the function may
 * be NaN somewhere in the box. The interval encloses the non-NaN values;
 * [NaN, NaN] when there are none. Records the decided branches in
 * ev->choice. */
fm_interval fm_eval_interval_nan(fm_evaluator *ev, const fm_interval box[4], int *maybe_nan);

#endif
