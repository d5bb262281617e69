// fit/ceres_shim.cc: the C interface of fit/ceres_shim.h over Ceres 2.x.
#include <config.h>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <algorithm>
#include <memory>
#include <mutex>
#include <vector>
#include <cfloat>
#include <ceres/ceres.h>
#include <Eigen/Dense>
#include <glog/logging.h>
#include "ceres_shim.h"

namespace {

// The user's function evaluates every residual at once; Ceres applies a
// robust loss per residual block. So each residual is its own block, and all
// blocks read from this cache, which calls the function (and forms the
// Jacobian, analytically or by central differences) once per parameter vector.
class Cache {
  public:
    Cache(int np, int nres, nbt_fit_residual_fn f, void *data, bool analytic)
        : np_(np), nres_(nres), f_(f), data_(data), analytic_(analytic), x_(np), r_(nres), J_((size_t)nres * np),
          rp_(nres), rm_(nres)
    {
    }
    // residual i (and its Jacobian row) at x; false if the function failed
    bool row(const double *x, int i, double *r, double *jrow)
    {
        std::lock_guard<std::mutex> lock(m_);
        bool same = valid_ && std::equal(x, x + np_, x_.begin());
        if (!same) {
            std::copy(x, x + np_, x_.begin());
            valid_ = true;
            have_jac_ = false;
            ok_ = f_(x, r_.data(), nullptr, data_) == 0;
        }
        if (ok_ && jrow && !have_jac_) {
            ok_ = analytic_ ? f_(x, r_.data(), J_.data(), data_) == 0 : central_differences(x);
            have_jac_ = ok_;
        }
        if (!ok_)
            return false;
        *r = r_[i];
        if (jrow)
            std::copy(J_.begin() + (size_t)i * np_, J_.begin() + (size_t)(i + 1) * np_, jrow);
        return true;
    }

  private:
    bool central_differences(const double *x)
    {
        std::vector<double> xp(x, x + np_);
        for (int j = 0; j < np_; j++) {
            double h = 6e-6 * std::max(std::fabs(x[j]), 1e-3);
            xp[j] = x[j] + h;
            if (f_(xp.data(), rp_.data(), nullptr, data_) != 0)
                return false;
            xp[j] = x[j] - h;
            if (f_(xp.data(), rm_.data(), nullptr, data_) != 0)
                return false;
            xp[j] = x[j];
            for (int i = 0; i < nres_; i++)
                J_[(size_t)i * np_ + j] = (rp_[i] - rm_[i]) / (2 * h);
        }
        return true;
    }
    int np_, nres_;
    nbt_fit_residual_fn f_;
    void *data_;
    bool analytic_, valid_ = false, have_jac_ = false, ok_ = false;
    std::vector<double> x_, r_, J_, rp_, rm_;
    std::mutex m_;
};

class RowCost : public ceres::CostFunction {
  public:
    RowCost(Cache *c, int np, int row) : c_(c), row_(row)
    {
        set_num_residuals(1);
        mutable_parameter_block_sizes()->push_back(np);
    }
    bool Evaluate(double const *const *p, double *r, double **jac) const override
    {
        return c_->row(p[0], row_, r, jac ? jac[0] : nullptr);
    }

  private:
    Cache *c_;
    int row_;
};

class Progress : public ceres::IterationCallback {
  public:
    Progress(const nbt_fit_options *o) : o_(o) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary &s) override
    {
        o_->progress(s.iteration, s.cost, o_->progress_data);
        return ceres::SOLVER_CONTINUE;
    }

  private:
    const nbt_fit_options *o_;
};

void set_text(char *dst, size_t n, const std::string &s)
{
    std::snprintf(dst, n, "%s", s.c_str());
}

// J^T J at the solution with unit-norm columns: its conditioning, rank and,
// when asked and of full rank, the covariance (J^T J)^-1.
void conditioning(ceres::Problem &problem, int np, int nres, bool want_cov, nbt_fit_summary *s)
{
    double cost;
    ceres::CRSMatrix crs;
    if (!problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, &crs))
        return;
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(nres, np);
    for (int i = 0; i < crs.num_rows; i++)
        for (int k = crs.rows[i]; k < crs.rows[i + 1]; k++)
            J(i, crs.cols[k]) = crs.values[k];
    Eigen::MatrixXd H = J.transpose() * J;
    if (!H.allFinite())
        return;
    Eigen::VectorXd d = H.diagonal().cwiseSqrt();
    for (int j = 0; j < np; j++)
        if (!(d(j) > 0)) // a parameter the residuals do not depend on: a zero row and column, eigenvalue 0
            d(j) = 1;
    Eigen::MatrixXd Hs = d.cwiseInverse().asDiagonal() * H * d.cwiseInverse().asDiagonal();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Hs);
    if (es.info() != Eigen::Success)
        return;
    const Eigen::VectorXd &lam = es.eigenvalues(); // ascending
    double top = lam(np - 1);
    s->rcond = top > 0 ? std::max(0.0, lam(0)) / top : 0;
    for (int j = 0; j < np; j++)
        s->rank += lam(j) > np * DBL_EPSILON * top;
    if (!want_cov || s->rank < np)
        return;
    Eigen::MatrixXd C = es.eigenvectors() * lam.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    C = d.cwiseInverse().asDiagonal() * C * d.cwiseInverse().asDiagonal();
    if (!C.allFinite())
        return;
    for (int i = 0; i < np; i++)
        for (int j = 0; j < np; j++)
            s->covariance[i * np + j] = C(i, j);
    s->covariance_ok = 1;
}

} // namespace

extern "C" void nbt_fit_options_default(nbt_fit_options *o)
{
    std::memset(o, 0, sizeof *o);
    o->max_iterations = 200;
    o->function_tolerance = 1e-12;
    o->gradient_tolerance = 1e-12;
    o->parameter_tolerance = 1e-12;
    o->threads = 1;
    o->loss = NBT_FIT_LOSS_NONE;
    o->loss_scale = 1;
}

extern "C" int nbt_fit_solve(int np, double *p, const double *lower, const double *upper, int nres,
                             nbt_fit_residual_fn f, void *data, const nbt_fit_options *o, nbt_fit_summary *s)
{
    std::memset(s, 0, sizeof *s);
    if (np < 1 || np > NBT_FIT_MAX_PARAMS || nres < np || !f || !p || !o) {
        set_text(s->termination, sizeof s->termination, "BAD_INPUT");
        set_text(s->message, sizeof s->message, "need 1 <= parameters <= 64, residuals >= parameters and a function");
        return 1;
    }
    for (int i = 0; i < np; i++)
        if (!std::isfinite(p[i]) || (lower && p[i] < lower[i]) || (upper && p[i] > upper[i])) {
            set_text(s->termination, sizeof s->termination, "BAD_INPUT");
            std::snprintf(s->message, sizeof s->message, "start value %d (%g) is not finite or outside its bounds", i,
                          p[i]);
            return 1;
        }
    try {
        std::vector<double> start(p, p + np);
        FLAGS_minloglevel = 3; // glog: nothing below FATAL on stderr (nbt reports through the summary)
        Cache cache(np, nres, f, data, o->analytic_jacobian != 0);
        ceres::Problem::Options po;
        ceres::Problem problem(po);
        for (int i = 0; i < nres; i++) {
            ceres::LossFunction *loss = nullptr;
            switch (o->loss) {
            case NBT_FIT_LOSS_HUBER: loss = new ceres::HuberLoss(o->loss_scale); break;
            case NBT_FIT_LOSS_CAUCHY: loss = new ceres::CauchyLoss(o->loss_scale); break;
            case NBT_FIT_LOSS_SOFT_L1: loss = new ceres::SoftLOneLoss(o->loss_scale); break;
            default: break;
            }
            problem.AddResidualBlock(new RowCost(&cache, np, i), loss, p);
        }
        for (int i = 0; i < np; i++) {
            if (lower && std::isfinite(lower[i]))
                problem.SetParameterLowerBound(p, i, lower[i]);
            if (upper && std::isfinite(upper[i]))
                problem.SetParameterUpperBound(p, i, upper[i]);
        }
        ceres::Solver::Options so;
        so.max_num_iterations = o->max_iterations;
        so.function_tolerance = o->function_tolerance;
        so.gradient_tolerance = o->gradient_tolerance;
        so.parameter_tolerance = o->parameter_tolerance;
        so.num_threads = o->threads > 0 ? o->threads : 1; /* the cache is locked: evaluation is serial */
        so.logging_type = ceres::SILENT;
        so.minimizer_progress_to_stdout = false;
        so.linear_solver_type = ceres::DENSE_QR;
        std::unique_ptr<Progress> cb;
        if (o->progress) {
            cb.reset(new Progress(o));
            so.callbacks.push_back(cb.get());
        }
        ceres::Solver::Summary sum;
        ceres::Solve(so, &problem, &sum);
        s->iterations = static_cast<int>(sum.iterations.size());
        s->initial_cost = sum.initial_cost;
        s->final_cost = sum.final_cost;
        s->converged = sum.termination_type == ceres::CONVERGENCE;
        s->usable = sum.IsSolutionUsable();
        set_text(s->termination, sizeof s->termination, ceres::TerminationTypeToString(sum.termination_type));
        set_text(s->message, sizeof s->message, sum.message);
        s->rcond = NAN;
        for (int i = 0; i < np * np; i++)
            s->covariance[i] = NAN;
        for (int i = 0; i < np; i++) {
            double scale = 1e-8 * std::fabs(start[i]);
            if (lower && std::isfinite(lower[i]) && p[i] <= lower[i] + std::max(scale, 1e-8 * std::fabs(lower[i])))
                s->at_bound[i] = -1;
            else if (upper && std::isfinite(upper[i]) && p[i] >= upper[i] - std::max(scale, 1e-8 * std::fabs(upper[i])))
                s->at_bound[i] = 1;
            s->nbound += s->at_bound[i] != 0;
        }
        if (s->usable)
            conditioning(problem, np, nres, o->covariance != 0, s);
        return s->usable ? 0 : 1;
    } catch (const std::exception &e) {
        set_text(s->termination, sizeof s->termination, "EXCEPTION");
        set_text(s->message, sizeof s->message, e.what());
    } catch (...) {
        set_text(s->termination, sizeof s->termination, "EXCEPTION");
        set_text(s->message, sizeof s->message, "unknown C++ exception");
    }
    return 1;
}
