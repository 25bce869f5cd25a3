/* The impacting bar's Moreau–Jean and Algorithm 2 steps as a plain C loop: the yardstick
 * of issue 19 §4 and issue 35 §2 ("the step at the machine's limit"), timed by
 * benches/c_loop.sh against `signorini bar` in one interleaved series.
 *
 * The same discrete problem as signorini's: N P1 rod elements (eq. 71, consistent mass),
 * θ-method (eq. 18) with M̂ = M + h²θ²K factored once as L D Lᵀ (tridiagonal), the
 * free forecast ḡ = g_k + h(θ U_free + (1−θ) U_k) of eq. 62 activating the tip's
 * contact, and the 1×1 LCP 0 ≤ U + e U_k ⊥ P ≥ 0 solved in closed form with
 * W = (M̂⁻¹)_00. No statistics, no checks, no output: only the arithmetic of a step.
 *
 * Algorithm 2 (`a2`) on the bar: its first round is the free step, whose end gap is the
 * forecast above, so the index set and the velocity level are Moreau–Jean's; then the
 * position projection of eq. 67–70 in the M̂⁻¹ metric (remark 3): q += τ M̂⁻¹ e_0 with
 * τ = −g_{k+1}/W, held as an equality where the impulse is positive in this step and the
 * last (the default `persistent` rule) and τ ≥ 0 elsewhere, fed back into the velocity
 * through −hθ M̂⁻¹K M̂⁻¹e_0 τ (eq. 56a) and into the next step's problem through
 * −hθ W_D τ; a row open in the last step that separates takes e = max(e, (1−θ)/θ).
 *
 * Usage: bar_step N h t_end repeats [gap [mj|a2]]; prints one JSON line: the median µs
 * per step of the repeats, the total impulse and the final tip velocity (to check it is
 * the same run). Built with -ffast-math, the process flushes subnormals to zero.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static int cmp(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv) {
    if (argc < 5 || argc > 7) {
        fprintf(stderr, "usage: %s N h t_end repeats [gap [mj|a2]]\n", argv[0]);
        return 2;
    }
    const int ne = atoi(argv[1]);
    const double h = atof(argv[2]), t_end = atof(argv[3]);
    const int repeats = atoi(argv[4]);
    const double gap = argc > 5 ? atof(argv[5]) : 0.0;
    const int a2 = argc > 6 && argv[6][0] == 'a';
    if (ne < 1 || !(h > 0) || !(t_end > 0) || repeats < 1 || !(gap >= 0)) {
        fprintf(stderr, "bad arguments\n");
        return 2;
    }
    const int n = ne + 1;
    const double L = 1.0, S = M_PI * 1e-4, E = 210e9, rho = 7800.0, v0 = -0.1, e = 0.0;
    const double theta = 0.5, le = L / ne;
    const long steps = lround(t_end / h);
    /* M and K as diagonals: main (md, kd) and sub (ms, ks; ms[i] couples i-1 and i) */
    double *md = calloc(n, sizeof *md), *ms = calloc(n, sizeof *ms);
    double *kd = calloc(n, sizeof *kd), *ks = calloc(n, sizeof *ks);
    for (int k = 0; k < ne; k++) {
        double m = rho * S * le / 6.0, s = E * S / le;
        md[k] += 2 * m, md[k + 1] += 2 * m, ms[k + 1] += m;
        kd[k] += s, kd[k + 1] += s, ks[k + 1] -= s;
    }
    /* M̂ = M + h²θ²K = L D Lᵀ: l[i] (i ≥ 1), dinv[i] */
    double *l = calloc(n, sizeof *l), *dinv = calloc(n, sizeof *dinv);
    const double c = h * h * theta * theta;
    double dprev = 0;
    for (int i = 0; i < n; i++) {
        double a = md[i] + c * kd[i], d;
        if (i == 0) {
            d = a;
        } else {
            double sub = ms[i] + c * ks[i];
            l[i] = sub / dprev;
            d = a - l[i] * sub;
        }
        dinv[i] = 1.0 / d;
        dprev = d;
    }
    /* w = M̂⁻¹ e_0, W = w_0 */
    double *w = calloc(n, sizeof *w), *x = calloc(n, sizeof *x);
    double *q = calloc(n, sizeof *q), *v = calloc(n, sizeof *v), *y = calloc(n, sizeof *y);
    w[0] = 1.0;
#define SOLVE(b)                                             \
    do {                                                     \
        double y_ = (b)[0];                                  \
        for (int i = 1; i < n; i++) {                        \
            y_ = (b)[i] - l[i] * y_;                         \
            (b)[i] = y_;                                     \
        }                                                    \
        double z_ = (b)[n - 1] * dinv[n - 1];                \
        (b)[n - 1] = z_;                                     \
        for (int i = n - 2; i >= 0; i--) {                   \
            z_ = (b)[i] * dinv[i] - l[i + 1] * z_;           \
            (b)[i] = z_;                                     \
        }                                                    \
    } while (0)
    SOLVE(w);
    const double W = w[0];
    /* wd = M̂⁻¹ K w (the projection's velocity feedback), W_D = wd_0 */
    double *wd = calloc(n, sizeof *wd);
    for (int i = 0; i < n; i++) {
        double a = kd[i] * w[i];
        if (i > 0) a += ks[i] * w[i - 1];
        if (i + 1 < n) a += ks[i + 1] * w[i + 1];
        wd[i] = a;
    }
    SOLVE(wd);
    const double WD = wd[0];
    double *times = calloc(repeats, sizeof *times);
    double impulse = 0;
    for (int r = 0; r < repeats; r++) {
        /* q is the displacement; the tip's gap is gap + q[0] */
        for (int i = 0; i < n; i++) q[i] = 0.0, v[i] = v0, y[i] = h * theta * v0;
        impulse = 0;
        double p_prev = 0;
        double t0 = now();
        for (long k = 0; k < steps; k++) {
            /* x = h (−K y), y = q + hθ v (formed by the previous step's update), K
             * tridiagonal: the end rows peeled so that the inner loop vectorizes */
            if (n == 1) {
                x[0] = -h * kd[0] * y[0];
            } else {
                x[0] = -h * (kd[0] * y[0] + ks[1] * y[1]);
                for (int i = 1; i < n - 1; i++)
                    x[i] = -h * (ks[i] * y[i - 1] + kd[i] * y[i] + ks[i + 1] * y[i + 1]);
                x[n - 1] = -h * (ks[n - 1] * y[n - 2] + kd[n - 1] * y[n - 1]);
            }
            SOLVE(x); /* x = v_free − v_k */
            double uk = v[0], ufree = v[0] + x[0];
            double gbar = gap + q[0] + h * (theta * ufree + (1 - theta) * uk);
            double p = 0, tau = 0;
            if (gbar <= 0) {
                double ee = e;
                if (a2 && p_prev <= 0 && uk > 0 && ee < (1 - theta) / theta) ee = (1 - theta) / theta;
                p = -(ufree + ee * uk) / W;
                if (p < 0) p = 0;
                if (a2) {
                    /* the decoupled fixed point of eq. 56 on scalars: the impulse
                     * with the feedback −hθ W_D τ of the last iterate, then τ */
                    const double glin = gap + q[0] + h * (1 - theta) * uk;
                    const int eq = p_prev > 0;
                    for (int it = 0; it < 50; it++) {
                        p = -(ufree - h * theta * WD * tau + ee * uk) / W;
                        if (p < 0) p = 0;
                        double un = ufree + W * p - h * theta * WD * tau;
                        double t = -(glin + h * theta * un) / W;
                        if (!(eq && p > 0) && t < 0) t = 0;
                        int done = fabs(t - tau) <= 1e-15 * fabs(t);
                        tau = t;
                        if (done) break;
                    }
                }
            }
            impulse += p;
            const double f = -h * theta * tau;
            if (tau != 0) {
                for (int i = 0; i < n; i++) {
                    double vn = v[i] + x[i] + p * w[i] + f * wd[i];
                    double qn = q[i] + h * (theta * vn + (1 - theta) * v[i]) + tau * w[i];
                    q[i] = qn;
                    v[i] = vn;
                    y[i] = qn + h * theta * vn;
                }
            } else {
                for (int i = 0; i < n; i++) {
                    double vn = v[i] + x[i] + p * w[i];
                    double qn = q[i] + h * (theta * vn + (1 - theta) * v[i]);
                    q[i] = qn;
                    v[i] = vn;
                    y[i] = qn + h * theta * vn;
                }
            }
            p_prev = p;
        }
        times[r] = (now() - t0) / steps * 1e6;
    }
    qsort(times, repeats, sizeof *times, cmp);
    printf("{\"us_per_step\": %.6g, \"steps\": %ld, \"total_impulse\": %.17g, \"tip_velocity\": %.17g}\n",
           times[repeats / 2], steps, impulse, v[n - 1]);
    return 0;
}
