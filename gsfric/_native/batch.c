/* Evaluate a CasADi-generated function over a batch of steps, on caller-owned buffers.
 *
 * Input k of step i starts at in[k] + i * in_stride[k]; a stride of 0 broadcasts one block
 * (the parameters) to every step. Output k of step i is written at out[k] + i * out_stride[k];
 * a NULL output is not computed. Steps are split between n_threads OpenMP threads, each with
 * its own work arrays. Returns the number of steps whose evaluation reported an error.
 */
#include <stdlib.h>
#ifdef _OPENMP
#include <omp.h>
#endif

typedef long long int casadi_int;
typedef int (*casadi_eval_t)(const double **arg, double **res, casadi_int *iw, double *w,
                             int mem);
typedef int (*casadi_work_t)(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                             casadi_int *sz_w);

long long gsfric_batch(casadi_eval_t eval, casadi_work_t work, int n_in, int n_out,
                       const double **in, const long long *in_stride, double **out,
                       const long long *out_stride, long long n, int n_threads)
{
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    long long failed = 0;
    work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    if (sz_arg < n_in) sz_arg = n_in;
    if (sz_res < n_out) sz_res = n_out;
    if (n_threads < 1) n_threads = 1;

#pragma omp parallel num_threads(n_threads) reduction(+ : failed)
    {
        const double **arg = malloc(sizeof(double *) * sz_arg);
        double **res = malloc(sizeof(double *) * sz_res);
        casadi_int *iw = malloc(sizeof(casadi_int) * (sz_iw > 0 ? sz_iw : 1));
        double *w = malloc(sizeof(double) * (sz_w > 0 ? sz_w : 1));
        if (!arg || !res || !iw || !w) {
            failed += n;
        } else {
            for (casadi_int k = n_in; k < sz_arg; ++k) arg[k] = 0;
            for (casadi_int k = n_out; k < sz_res; ++k) res[k] = 0;
#pragma omp for schedule(static)
            for (long long i = 0; i < n; ++i) {
                for (int k = 0; k < n_in; ++k) arg[k] = in[k] + i * in_stride[k];
                for (int k = 0; k < n_out; ++k) res[k] = out[k] ? out[k] + i * out_stride[k] : 0;
                if (eval(arg, res, iw, w, 0)) failed += 1;
            }
        }
        free(arg);
        free(res);
        free(iw);
        free(w);
    }
    return failed;
}

/* The same contract for a SIMD-over-steps function of derive/simd.py, whose own loop walks the
 * steps several at a time: the steps are split into one contiguous range per thread. */
typedef void (*batch_eval_t)(const double **in, const long long *in_stride, double **out,
                             const long long *out_stride, long long n);

#define MAX_ARGS 64

long long gsfric_batch_simd(batch_eval_t eval, int n_in, int n_out, const double **in,
                            const long long *in_stride, double **out,
                            const long long *out_stride, long long n, int n_threads)
{
    if (n_in > MAX_ARGS || n_out > MAX_ARGS) return n;
    if (n_threads < 1) n_threads = 1;
    if (n < 64 * n_threads) n_threads = 1;
    if (n_threads == 1) {
        eval(in, in_stride, out, out_stride, n);
        return 0;
    }
#pragma omp parallel num_threads(n_threads)
    {
        int t = 0, nt = 1;
#ifdef _OPENMP
        t = omp_get_thread_num();
        nt = omp_get_num_threads();
#endif
        long long start = n * t / nt, stop = n * (t + 1) / nt;
        const double *my_in[MAX_ARGS];
        double *my_out[MAX_ARGS];
        for (int k = 0; k < n_in; ++k) my_in[k] = in[k] + start * in_stride[k];
        for (int k = 0; k < n_out; ++k) my_out[k] = out[k] ? out[k] + start * out_stride[k] : 0;
        if (stop > start) eval(my_in, in_stride, my_out, out_stride, stop - start);
    }
    return 0;
}
