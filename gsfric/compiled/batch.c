/* Evaluate a generated function over a batch of steps, on caller-owned buffers, with the step
 * flags computed in the same pass.
 *
 * Input k of step i starts at in[k] + i * in_stride[k]; a stride of 0 broadcasts one block
 * (the parameters) to every step. Output k of step i is written at out[k] + i * out_stride[k]
 * (rows are contiguous: the stride is the output's size); a NULL output is not computed.
 *
 * A function is evaluated by its SIMD-over-steps version (derive/simd.py) when it has one and
 * every input but the first is broadcast, otherwise by CasADi's per-step function.
 *
 * Concurrency: nothing here is shared between calls. Every call builds its own argument arrays
 * (on the stack) and work arrays (malloc); the function description and the flag settings are
 * only read. Several threads may call at once with different output buffers.
 *
 * Threads: a call on n_threads > 1 splits the steps into contiguous ranges, runs one in the
 * calling thread and each other in a POSIX thread created for the call, and joins them. No
 * thread ever waits by spinning: a busy core delays only its own range.
 *
 * Motion input: instead of input 0 (the state x, 24 values per step), a call may give the six
 * arrays of a motion (position (N, 3), rotation (N, 3, 3) row-major, velocity, omega,
 * acceleration, alpha (N, 3), C-contiguous). Each range then lays out x for blocks of
 * XBLOCK steps in a small buffer of its own and evaluates block after block: no state array of
 * N steps, no pass over the motion before the evaluation. The same blocks give the outputs the
 * flags need but the caller did not ask for (a per-range scratch buffer).
 *
 * Rotation test: a call without flags (the control loop's) may still test every step's state
 * for a rotation block that is not a rotation (the test of FLAG_ROTATION, with its settings):
 * such a step's outputs are NaN and the call reports the first of them. The test reads each
 * block of states right after its evaluation, while they are in the cache.
 */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

typedef long long int casadi_int;
typedef int (*casadi_eval_t)(const double **arg, double **res, casadi_int *iw, double *w,
                             int mem);
typedef int (*casadi_work_t)(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                             casadi_int *sz_w);
typedef void (*batch_eval_t)(const double **in, const long long *in_stride, double **out,
                             const long long *out_stride, long long n, long long *bad);

#define MAX_ARGS 64
#define MAX_THREADS 64
#define MIN_STEPS_PER_THREAD 2048  /* below this, creating a thread costs more than it saves */
#define BLOCK 32                   /* steps evaluated before their flags (64 KB of outputs, in cache) */
#define XBLOCK 4096                /* steps per block of a motion input (x: 768 KB); as long as a
                                      batch whose outputs go past the caches (STREAM_STEPS) */
#define X_SIZE 24                  /* p (3), T (9), v, omega, a, alpha (3 each) */
#define CHECK_STEPS 4096           /* steps per SIMD call when their rotations are tested: their
                                      states (768 KB) are still in the cache for the test, and
                                      every call streams its outputs (STREAM_STEPS) */

typedef struct {
    batch_eval_t simd;   /* NULL: none */
    casadi_eval_t eval;
    casadi_work_t work;
    int n_in, n_out;
} gsfric_fn;

/* step flags: begin (this block is copied verbatim into the library of `gsfric export`) */
/* The flags' bits: the same as gsfric/evaluation/flags.py's FLAG_* */
#define FLAG_NONFINITE 1
#define FLAG_STROKE 2
#define FLAG_SINGULAR 4
#define FLAG_UNIVERSAL 8
#define FLAG_COUPLING 16
#define FLAG_ROTATION 32

typedef struct {
    int d, s2, h;        /* output indices of leg lengths (6), s2 (6), singularity measure (1) */
    int has_stroke;
    double stroke_lo, stroke_hi;
    double universal_limit;   /* flag s2 < this */
    double singular_limit;    /* flag h < this */
    long long x_size;         /* values of input 0 per step */
    int cc, f0;               /* output indices of coupling_change (6) and F0 (6), or -1 */
    double coupling_tol;      /* flag |cc| > coupling_tol (1 + |F0|) on a finite step */
    long long rotation;       /* offset of the rotation block T (9 values, row-major) in
                                 input 0, or -1: no rotation flag */
    double rotation_tol;      /* flag an entry of |T^T T - I| above this, or det T < 0 */
} gsfric_flags;

/* FLAG_ROTATION when the rotation block T of state x is not a rotation (an entry of
 * |T^T T - I| above fl->rotation_tol, or det T < 0: a scaled, sheared or mirrored matrix),
 * else 0. NaN entries pass (they are FLAG_NONFINITE). Straight code, no branch: a few
 * nanoseconds per step in a loop over steps. */
static inline long long rotation_flag(const gsfric_flags *fl, const double *x)
{
    if (fl->rotation < 0) return 0;
    const double *T = x + fl->rotation;
    double tol = fl->rotation_tol;
    /* T^T T - I: the products of T's columns j and k, j <= k */
    double g00 = T[0] * T[0] + T[3] * T[3] + T[6] * T[6] - 1.0;
    double g11 = T[1] * T[1] + T[4] * T[4] + T[7] * T[7] - 1.0;
    double g22 = T[2] * T[2] + T[5] * T[5] + T[8] * T[8] - 1.0;
    double g01 = T[0] * T[1] + T[3] * T[4] + T[6] * T[7];
    double g02 = T[0] * T[2] + T[3] * T[5] + T[6] * T[8];
    double g12 = T[1] * T[2] + T[4] * T[5] + T[7] * T[8];
    double det = T[0] * (T[4] * T[8] - T[7] * T[5]) - T[3] * (T[1] * T[8] - T[7] * T[2])
                 + T[6] * (T[1] * T[5] - T[4] * T[2]);
    int bad = (fabs(g00) > tol) | (fabs(g11) > tol) | (fabs(g22) > tol) | (fabs(g01) > tol)
              | (fabs(g02) > tol) | (fabs(g12) > tol) | (det < 0.0);
    return bad ? FLAG_ROTATION : 0;
}

/* The bits of one step from its outputs (NULL: not computed, that flag not raised) and
 * whether every value of the step is finite. The geometric causes are tested on the values
 * as computed (a NaN compares false), so that a step made non-finite by one of them still
 * names it. */
static long long step_flags(const gsfric_flags *fl, int finite, const double *D,
                            const double *s2, const double *h, const double *cc,
                            const double *F0)
{
    long long f = 0;
    if (D && fl->has_stroke)
        for (int j = 0; j < 6; ++j)
            if (D[j] < fl->stroke_lo || D[j] > fl->stroke_hi) f |= FLAG_STROKE;
    if (s2)
        for (int j = 0; j < 6; ++j)
            if (s2[j] < fl->universal_limit) f |= FLAG_UNIVERSAL;
    if (h && h[0] < fl->singular_limit) f |= FLAG_SINGULAR;
    if (finite && cc && F0)
        for (int j = 0; j < 6; ++j)
            if (fabs(cc[j]) > fl->coupling_tol * (1.0 + fabs(F0[j]))) f |= FLAG_COUPLING;
    if (!finite) f |= FLAG_NONFINITE;
    return f;
}
/* step flags: end */

typedef struct {
    const gsfric_fn *fn;
    const double **in;
    const long long *in_stride;
    double **out;
    const long long *out_stride;
    const gsfric_flags *flags;
    long long *flag;
    int use_simd;
    long long start, stop;
    long long failed;
    const double *const *motion;  /* NULL, or the six arrays of a motion in place of input 0 */
    const gsfric_flags *check;    /* NULL, or (without flags) the rotation test of input 0 */
    long long rejected;           /* the first step that fails `check`, or -1 */
} range_task;

/* 1 when none of y[0..n) is infinite or NaN (exponent bits all set), by integer operations
 * that the compiler can vectorise */
static int all_finite(const double *y, long long n)
{
    const unsigned long long exponent = 0x7ff0000000000000ULL;
    unsigned long long bad = 0;
    for (long long j = 0; j < n; ++j) {
        unsigned long long bits;
        memcpy(&bits, y + j, sizeof bits);
        bad |= (bits & exponent) == exponent;
    }
    return !bad;
}

/* Step i's row of output k, or NULL when k < 0 or that output is not computed */
static const double *step_row(const range_task *t, int k, long long i)
{
    return k >= 0 && t->out[k] ? t->out[k] + i * t->out_stride[k] : NULL;
}

/* Set every output of step i to NaN */
static void clear_step(const range_task *t, long long i)
{
    for (int k = 0; k < t->fn->n_out; ++k) {
        if (!t->out[k]) continue;
        double *y = t->out[k] + i * t->out_stride[k];
        for (long long j = 0; j < t->out_stride[k]; ++j) y[j] = NAN;
    }
}

/* Flag steps s..e-1 into t->flag. With `checked`, t->flag[i] already holds 1 where some
 * output of step i is non-finite (the SIMD function's `bad`), else the outputs are checked.
 * A step flagged FLAG_ROTATION has no other flag, and NaN outputs as a non-finite one. */
static void flag_steps(const range_task *t, long long s, long long e, int checked)
{
    const gsfric_flags *fl = t->flags;
    int n_out = t->fn->n_out;
    for (long long i = s; i < e; ++i) {
        int finite = 1;
        const double *x = t->in[0] + i * t->in_stride[0];
        finite &= all_finite(x, fl->x_size);
        if (checked)
            finite &= t->flag[i] == 0;
        else
            for (int k = 0; k < n_out; ++k)
                if (t->out[k])
                    finite &= all_finite(t->out[k] + i * t->out_stride[k], t->out_stride[k]);
        const double *D = step_row(t, fl->d, i), *s2 = step_row(t, fl->s2, i);
        const double *h = step_row(t, fl->h, i);
        const double *cc = step_row(t, fl->f0, i) ? step_row(t, fl->cc, i) : NULL;
        const double *F0 = cc ? step_row(t, fl->f0, i) : NULL;
        long long rotation = rotation_flag(fl, x);
        long long f = rotation ? rotation : step_flags(fl, finite, D, s2, h, cc, F0);
        if (!finite || rotation) clear_step(t, i);
        t->flag[i] = f;
    }
}

/* 1 when some step of s..e-1 fails the rotation test of t->check (one pass, no branch per
 * step: a few multiplications per step, on states the evaluation has just read) */
static int any_rejected(const range_task *t, long long s, long long e)
{
    const double *x = t->in[0];
    long long stride = t->in_stride[0], bad = 0;
    for (long long i = s; i < e; ++i) bad |= rotation_flag(t->check, x + i * stride);
    return bad != 0;
}

/* After the evaluation of steps s..e-1 of which some fail the rotation test: their outputs
 * NaN, the first of them in t->rejected (unless an earlier one is there) */
static void reject_steps(range_task *t, long long s, long long e)
{
    for (long long i = s; i < e; ++i) {
        if (!rotation_flag(t->check, t->in[0] + i * t->in_stride[0])) continue;
        clear_step(t, i);
        if (t->rejected < 0) t->rejected = i;
    }
}

static void *run_range(void *arg);

/* Lay out the states of steps s..e-1 of a motion into x (rows of X_SIZE values). */
static void layout_states(const double *const *m, long long s, long long e, double *x)
{
    static const int width[6] = {3, 9, 3, 3, 3, 3};
    for (long long i = s; i < e; ++i) {
        double *row = x + (i - s) * X_SIZE;
        for (int k = 0, o = 0; k < 6; o += width[k], ++k)
            for (int j = 0; j < width[k]; ++j) row[o + j] = m[k][i * width[k] + j];
    }
}

/* The output indices the flags read (-1: none) */
static int flag_outputs(const gsfric_flags *fl, int *k)
{
    if (!fl) return 0;
    k[0] = fl->d; k[1] = fl->s2; k[2] = fl->h; k[3] = fl->cc; k[4] = fl->f0;
    return 5;
}

/* A range evaluated block by block: with a motion, x laid out per block; outputs the flags
 * need but the caller does not get are written to a scratch buffer of this range. */
static void run_blocks(range_task *t)
{
    const gsfric_fn *fn = t->fn;
    int n_in = fn->n_in, n_out = fn->n_out;
    long long length = t->stop - t->start;
    long long blk = length < XBLOCK ? length : XBLOCK;
    double *x = NULL, *scratch[MAX_ARGS] = {0};
    int need[5], n_need = flag_outputs(t->flags, need), ok = 1;
    if (t->motion) ok &= (x = malloc(sizeof(double) * X_SIZE * blk)) != NULL;
    for (int q = 0; q < n_need; ++q) {
        int k = need[q];
        if (k >= 0 && k < n_out && !t->out[k] && !scratch[k])
            ok &= (scratch[k] = malloc(sizeof(double) * t->out_stride[k] * blk)) != NULL;
    }
    if (!ok) {
        t->failed = length;
        goto done;
    }
    for (long long s = t->start; s < t->stop; s += blk) {
        long long e = s + blk < t->stop ? s + blk : t->stop;
        const double *in[MAX_ARGS];
        long long in_stride[MAX_ARGS];
        double *out[MAX_ARGS];
        for (int k = 0; k < n_in; ++k) {
            in[k] = t->in[k] ? t->in[k] + s * t->in_stride[k] : NULL;
            in_stride[k] = t->in_stride[k];
        }
        if (t->motion) {
            layout_states(t->motion, s, e, x);
            in[0] = x;
            in_stride[0] = X_SIZE;
        }
        for (int k = 0; k < n_out; ++k)
            out[k] = t->out[k] ? t->out[k] + s * t->out_stride[k] : scratch[k];
        range_task block = {fn, in, in_stride, out, t->out_stride, t->flags,
                            t->flag ? t->flag + s : NULL, t->use_simd, 0, e - s, 0, NULL,
                            t->check, -1};
        run_range(&block);
        t->failed += block.failed;
        if (t->rejected < 0 && block.rejected >= 0) t->rejected = s + block.rejected;
    }
done:
    free(x);
    for (int k = 0; k < n_out; ++k) free(scratch[k]);
}

/* 1 when the range must go block by block (a motion, or flags on outputs not asked for) */
static int blocked(const range_task *t)
{
    int need[5], n_need = flag_outputs(t->flags, need);
    if (t->motion) return 1;
    for (int q = 0; q < n_need; ++q)
        if (need[q] >= 0 && need[q] < t->fn->n_out && !t->out[need[q]]) return 1;
    return 0;
}

/* A range by the SIMD-over-steps function: one call over the range (long ranges stream
 * their outputs past the caches; the non-finite outputs are found on the vectors before they
 * are written), or with t->check one call per CHECK_STEPS steps (the last taking the rest),
 * each followed by the rotation test of its states while the call has left them in the
 * cache (before the call, the test would read them from memory: a pass bound by the memory,
 * where the evaluation hides those reads behind its arithmetic). */
static void run_simd(range_task *t)
{
    const gsfric_fn *fn = t->fn;
    long long step = t->check ? CHECK_STEPS : t->stop - t->start;
    for (long long s = t->start; s < t->stop; s += step) {
        long long e = t->stop - s < 2 * step ? t->stop : s + step;
        const double *in[MAX_ARGS];
        double *out[MAX_ARGS];
        for (int k = 0; k < fn->n_in; ++k) in[k] = t->in[k] + s * t->in_stride[k];
        for (int k = 0; k < fn->n_out; ++k)
            out[k] = t->out[k] ? t->out[k] + s * t->out_stride[k] : 0;
        fn->simd(in, t->in_stride, out, t->out_stride, e - s, t->flags ? t->flag + s : NULL);
        if (t->flags) flag_steps(t, s, e, 1);
        if (t->check && any_rejected(t, s, e)) reject_steps(t, s, e);
        if (e == t->stop) break;
    }
}

static void *run_range(void *arg)
{
    range_task *t = arg;
    const gsfric_fn *fn = t->fn;
    int n_in = fn->n_in, n_out = fn->n_out;
    if (blocked(t)) {
        run_blocks(t);
        return NULL;
    }
    casadi_int sz_arg = 0, sz_res = 0, sz_iw = 0, sz_w = 0;
    const double **carg = NULL;
    double **cres = NULL;
    casadi_int *iw = NULL;
    double *w = NULL;
    if (!t->use_simd) {
        fn->work(&sz_arg, &sz_res, &sz_iw, &sz_w);
        if (sz_arg < n_in) sz_arg = n_in;
        if (sz_res < n_out) sz_res = n_out;
        carg = calloc(sz_arg, sizeof(double *));
        cres = calloc(sz_res, sizeof(double *));
        iw = malloc(sizeof(casadi_int) * (sz_iw > 0 ? sz_iw : 1));
        w = malloc(sizeof(double) * (sz_w > 0 ? sz_w : 1));
        if (!carg || !cres || !iw || !w) {
            t->failed = t->stop - t->start;
            goto done;
        }
    }
    if (t->use_simd) {
        run_simd(t);
        goto done;
    }
    long long block = t->flags || t->check ? BLOCK : t->stop - t->start;
    for (long long s = t->start; s < t->stop; s += block) {
        long long e = s + block < t->stop ? s + block : t->stop;
        for (long long i = s; i < e; ++i) {
            for (int k = 0; k < n_in; ++k) carg[k] = t->in[k] + i * t->in_stride[k];
            for (int k = 0; k < n_out; ++k)
                cres[k] = t->out[k] ? t->out[k] + i * t->out_stride[k] : 0;
            if (fn->eval(carg, cres, iw, w, 0)) t->failed += 1;
        }
        if (t->flags) flag_steps(t, s, e, 0);
        if (t->check && any_rejected(t, s, e)) reject_steps(t, s, e);
    }
done:
    free(carg);
    free(cres);
    free(iw);
    free(w);
    return NULL;
}

/* Evaluate fn over n steps (and flag them when flags is not NULL: flag[i] gets step i's bits).
 * With check instead of flags: the rotation test of check (rotation_flag) on the state of
 * every step; the steps that fail it get NaN outputs, and *rejected the first of them (-1:
 * none). Returns the number of steps whose evaluation reported an error. */
long long gsfric_run(const gsfric_fn *fn, const double **in, const long long *in_stride,
                     double **out, const long long *out_stride, long long n, int n_threads,
                     const gsfric_flags *flags, long long *flag, const double *const *motion,
                     const gsfric_flags *check, long long *rejected)
{
    if (rejected) *rejected = -1;
    if (flags || !rejected) check = NULL;
    if (fn->n_in > MAX_ARGS || fn->n_out > MAX_ARGS) return n;
    if (n <= 0) return 0;
    int use_simd = fn->simd != NULL;
    for (int k = 1; k < fn->n_in; ++k) use_simd &= in_stride[k] == 0;
    long long most = n / MIN_STEPS_PER_THREAD;
    if (n_threads > most) n_threads = (int)most;
    if (n_threads > MAX_THREADS) n_threads = MAX_THREADS;
    if (n_threads < 1) n_threads = 1;
    range_task tasks[MAX_THREADS];
    pthread_t threads[MAX_THREADS];
    int started[MAX_THREADS] = {0};
    /* range boundaries on multiples of 8 steps: every range's groups of steps then start
     * where the first range's do (whole 64-byte lines of every output row). No range is
     * empty: each thread has at least MIN_STEPS_PER_THREAD steps before the rounding, which
     * moves a boundary by at most 7 */
    for (int k = 0; k < n_threads; ++k) {
        long long lo = k ? (n * k / n_threads) & ~7LL : 0;
        long long hi = k + 1 < n_threads ? (n * (k + 1) / n_threads) & ~7LL : n;
        tasks[k] = (range_task){fn, in, in_stride, out, out_stride, flags, flag, use_simd,
                                lo, hi, 0, motion, check, -1};
    }
    for (int k = 1; k < n_threads; ++k)
        started[k] = pthread_create(&threads[k], NULL, run_range, &tasks[k]) == 0;
    run_range(&tasks[0]);
    for (int k = 1; k < n_threads; ++k) {
        if (started[k])
            pthread_join(threads[k], NULL);
        else
            run_range(&tasks[k]);  /* no thread to be had: run it here */
    }
    long long failed = 0;
    for (int k = 0; k < n_threads; ++k) {
        failed += tasks[k].failed;
        if (check && *rejected < 0) *rejected = tasks[k].rejected;
    }
    return failed;
}

/* A control-loop call's status: 0; k + 1 when step k is the first whose state fails the
 * rotation test; -m when the evaluation failed at m steps */
static long long status(long long failed, long long rejected)
{
    return failed ? -failed : rejected + 1;
}

/* The control loop's call: input 0 is x, the others are fixed[k] (read only, shared); only
 * output `index` is computed, into y; every state has the rotation test of check (NULL:
 * none). The argument arrays are this call's own. Returns the call's status (`status`). */
long long gsfric_run_one(const gsfric_fn *fn, const double **fixed, const long long *in_stride,
                         const long long *out_stride, const double *x, int index, double *y,
                         long long n, int n_threads, const gsfric_flags *check)
{
    const double *in[MAX_ARGS];
    double *out[MAX_ARGS];
    long long rejected;
    if (fn->n_in > MAX_ARGS || fn->n_out > MAX_ARGS || index < 0 || index >= fn->n_out)
        return -n;
    for (int k = 0; k < fn->n_in; ++k) in[k] = fixed[k];
    in[0] = x;
    for (int k = 0; k < fn->n_out; ++k) out[k] = 0;
    out[index] = y;
    long long failed = gsfric_run(fn, in, in_stride, out, out_stride, n, n_threads, NULL, NULL,
                                  NULL, check, &rejected);
    return status(failed, rejected);
}

/* The same from a motion's six arrays (see the top of this file) instead of x. */
long long gsfric_run_one_motion(const gsfric_fn *fn, const double **fixed,
                                const long long *in_stride, const long long *out_stride,
                                const double *p, const double *T, const double *v,
                                const double *w, const double *a, const double *alpha,
                                int index, double *y, long long n, int n_threads,
                                const gsfric_flags *check)
{
    const double *in[MAX_ARGS];
    double *out[MAX_ARGS];
    const double *motion[6] = {p, T, v, w, a, alpha};
    long long rejected;
    if (fn->n_in > MAX_ARGS || fn->n_out > MAX_ARGS || index < 0 || index >= fn->n_out)
        return -n;
    for (int k = 0; k < fn->n_in; ++k) in[k] = fixed[k];
    in[0] = NULL;
    for (int k = 0; k < fn->n_out; ++k) out[k] = 0;
    out[index] = y;
    long long failed = gsfric_run(fn, in, in_stride, out, out_stride, n, n_threads, NULL, NULL,
                                  motion, check, &rejected);
    return status(failed, rejected);
}

/* The control loop's calls can take NumPy arrays as Python objects: their data pointer is
 * then read here, in PyArrayObject_fields.data, the first field after the object header (two
 * pointer-sized fields), which costs far less than asking NumPy for it in Python (a ctypes
 * object per array). gsfric/native.py checks at load time that this reads the same address as
 * NumPy's ``ctypes.data`` and uses the pointers otherwise. */
static void *array_data(const void *obj)
{
    return *(void *const *)((const char *)obj + 2 * sizeof(void *));
}

long long gsfric_array_data(const void *obj) { return (long long)array_data(obj); }

long long gsfric_run_one_objects(const gsfric_fn *fn, const double **fixed,
                                 const long long *in_stride, const long long *out_stride,
                                 const void *x, int index, const void *y, long long n,
                                 int n_threads, const gsfric_flags *check)
{
    return gsfric_run_one(fn, fixed, in_stride, out_stride, array_data(x), index,
                          array_data(y), n, n_threads, check);
}

long long gsfric_run_one_motion_objects(const gsfric_fn *fn, const double **fixed,
                                        const long long *in_stride,
                                        const long long *out_stride, const void *p,
                                        const void *T, const void *v, const void *w,
                                        const void *a, const void *alpha, int index,
                                        const void *y, long long n, int n_threads,
                                        const gsfric_flags *check)
{
    return gsfric_run_one_motion(fn, fixed, in_stride, out_stride, array_data(p),
                                 array_data(T), array_data(v), array_data(w), array_data(a),
                                 array_data(alpha), index, array_data(y), n, n_threads, check);
}

/* The control loop's call with its fixed arguments in one structure, built once per bound
 * callable (read only), and the arrays in one Python tuple: the fewer arguments ctypes
 * converts per call, the shorter the call. The tuple's items are read from CPython's tuple
 * structure (the object header, the size, then the item pointers); gsfric/native.py checks
 * at load time that this reads the same objects as Python does, and uses the calls above
 * otherwise. */
typedef struct {
    const gsfric_fn *fn;
    const double **fixed;
    const long long *in_stride;
    const long long *out_stride;
    int index;
    int n_threads;
    const gsfric_flags *check;  /* the rotation test of every state, or NULL */
} gsfric_bound;

static const void *tuple_item(const void *tuple, int k)
{
    return ((const void *const *)((const char *)tuple + 3 * sizeof(void *)))[k];
}

long long gsfric_tuple_item(const void *tuple, int k) { return (long long)tuple_item(tuple, k); }

/* arrays: (x, out) */
long long gsfric_bound_states(const gsfric_bound *b, const void *arrays, long long n)
{
    return gsfric_run_one(b->fn, b->fixed, b->in_stride, b->out_stride,
                          array_data(tuple_item(arrays, 0)), b->index,
                          array_data(tuple_item(arrays, 1)), n, b->n_threads, b->check);
}

/* arrays: (position, rotation, velocity, omega, acceleration, alpha, out) */
long long gsfric_bound_motion(const gsfric_bound *b, const void *arrays, long long n)
{
    const double *m[6];
    for (int k = 0; k < 6; ++k) m[k] = array_data(tuple_item(arrays, k));
    return gsfric_run_one_motion(b->fn, b->fixed, b->in_stride, b->out_stride, m[0], m[1],
                                 m[2], m[3], m[4], m[5], b->index,
                                 array_data(tuple_item(arrays, 6)), n, b->n_threads,
                                 b->check);
}

#ifdef GSFRIC_PER_STEP_ONLY
/* A build without the SIMD-over-steps source (meson.build) has no vectors over steps */
int gsfric_simd_lanes(void) { return 0; }
#endif

/* The widest instruction set of this CPU among the builds gsfric ships for x86-64 (4:
 * x86-64-v4 with AVX-512, 3: x86-64-v3 with AVX2 and FMA, 1: the x86-64 baseline); 0 on other
 * architectures. Called in the baseline build only, which runs on every CPU of its
 * architecture; gsfric/compiled/native.py then loads the widest build the CPU can run. */
int gsfric_cpu_level(void)
{
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
    __builtin_cpu_init();
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12
    /* the levels as the compiler defines them (all of their features, OS support included) */
    if (__builtin_cpu_supports("x86-64-v4"))
        return 4;
    if (__builtin_cpu_supports("x86-64-v3"))
        return 3;
    return 1;
#else
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq")
        && __builtin_cpu_supports("avx512cd") && __builtin_cpu_supports("avx512bw")
        && __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx2")
        && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2"))
        return 4;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")
        && __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2"))
        return 3;
    return 1;
#endif
#else
    return 0;
#endif
}
