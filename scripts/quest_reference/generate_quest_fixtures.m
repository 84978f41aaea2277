% Generates tests/study/fixtures/quest_psychtoolbox.json from the REAL Psychtoolbox Quest*.m.
%
%   apt-get install octave octave-psychtoolbox-3        (Debian; Psychtoolbox 3.0.18)
%   octave --no-gui -q scripts/quest_reference/generate_quest_fixtures.m
%
% Each case fixes QuestCreate's arguments and the trials: either the intensities themselves, or a
% placement rule (quantile / mean / mode, optional first intensity) plus the responses. Responses
% of simulated cases were drawn here once (QuestSimulate with a seeded rand) and are stored, so the
% C++ test replays exactly the same trials. The script records what Psychtoolbox computes: the
% intensities it placed, xThreshold, quantileOrder, Mean/Sd/Mode/Quantile, Quantile at several
% orders, P, Pdf, QuestRecompute's mean, and QuestBetaAnalysis, plus the errors it raises for
% invalid parameters. Numbers are written with 17 significant digits.

1;

function s = num(x)
  if isnan(x)
    s = 'null';
  elseif isinf(x)
    if x > 0, s = '"inf"'; else, s = '"-inf"'; end
  else
    s = sprintf('%.17g', x);
  end
end

function s = nums(v)
  parts = arrayfun(@num, v, 'UniformOutput', false);
  s = ['[' strjoin(parts, ',') ']'];
end

function s = str(t)
  t = strrep(t, '\', '\\');
  t = strrep(t, '"', '\"');
  s = ['"' t '"'];
end

function q = create(c)
  if isempty(c.range)
    q = QuestCreate(c.tGuess, c.tGuessSd, c.pThreshold, c.beta, c.delta, c.gamma, c.grain);
  else
    q = QuestCreate(c.tGuess, c.tGuessSd, c.pThreshold, c.beta, c.delta, c.gamma, c.grain, c.range);
  end
end

function x = place(q, rule)
  switch rule
    case 'quantile', x = QuestQuantile(q);
    case 'mean', x = QuestMean(q);
    case 'mode', x = QuestMode(q);
  end
end

% Runs a case; when c.simulate_t_actual is set, responses are drawn with QuestSimulate.
function [out, c] = run_case(c)
  q = create(c);
  lastwarn('');
  out = {};
  out{end+1} = sprintf('"dim":%d', q.dim);
  out{end+1} = sprintf('"gamma_used":%s', num(q.gamma));
  out{end+1} = sprintf('"x_threshold":%s', num(q.xThreshold));
  out{end+1} = sprintf('"quantile_order":%s', num(q.quantileOrder));
  out{end+1} = sprintf('"prior_quantile":%s', num(QuestQuantile(q)));
  out{end+1} = sprintf('"prior_mode":%s', num(QuestMode(q)));
  used = zeros(1, c.trials);
  checkpoints = {};
  for k = 1:c.trials
    if ~isempty(c.intensities)
      x = c.intensities(k);
    elseif k == 1 && ~isempty(c.first)
      x = c.first;
    else
      x = place(q, c.placement);
    end
    if isfield(c, 'simulate_t_actual') && ~isempty(c.simulate_t_actual)
      c.responses(k) = QuestSimulate(q, x, c.simulate_t_actual);
    end
    used(k) = x;
    q = QuestUpdate(q, x, c.responses(k));
    if c.checkpoint_every > 0 && mod(k, c.checkpoint_every) == 0
      checkpoints{end+1} = sprintf('{"trial":%d,"intensity":%s,"mean":%s,"sd":%s,"mode":%s,"quantile":%s}', ...
        k, num(x), num(QuestMean(q)), num(QuestSd(q)), num(QuestMode(q)), num(QuestQuantile(q)));
    end
  end
  if c.store_intensities
    out{end+1} = sprintf('"intensities_used":%s', nums(used));
  end
  out{end+1} = sprintf('"checkpoints":[%s]', strjoin(checkpoints, ','));
  out{end+1} = sprintf('"mean":%s', num(QuestMean(q)));
  out{end+1} = sprintf('"sd":%s', num(QuestSd(q)));
  out{end+1} = sprintf('"mode":%s', num(QuestMode(q)));
  out{end+1} = sprintf('"quantile":%s', num(QuestQuantile(q)));
  orders = [0 1e-6 0.01 0.05 0.25 0.5 0.75 0.95 0.99 1];
  qs = arrayfun(@(o) QuestQuantile(q, o), orders);
  out{end+1} = sprintf('"quantile_orders":%s', nums(orders));
  out{end+1} = sprintf('"quantiles":%s', nums(qs));
  px = [-1e3, q.x2(1) - 1, q.x2(1), -0.123, 0, 0.0049, 0.3, q.x2(end), q.x2(end) + 1, 1e3];
  out{end+1} = sprintf('"p_x":%s', nums(px));
  out{end+1} = sprintf('"p":%s', nums(arrayfun(@(x) QuestP(q, x), px)));
  pt = c.tGuess + [-1e3, -0.37, 0, 0.004999, 0.005, 0.21, 1e3];
  out{end+1} = sprintf('"pdf_t":%s', nums(pt));
  out{end+1} = sprintf('"pdf":%s', nums(arrayfun(@(t) QuestPdf(q, t), pt)));
  r = QuestRecompute(q);
  out{end+1} = sprintf('"recompute_mean":%s', num(QuestMean(r)));
  out{end+1} = sprintf('"recompute_sd":%s', num(QuestSd(r)));
  if c.beta_analysis
    try
      [ba_t, ba_sd, ba_beta, ba_beta_sd] = beta_analysis_values(q);
      out{end+1} = sprintf('"beta_analysis":{"t":%s,"sd":%s,"beta":%s,"beta_sd":%s}', ...
        num(ba_t), num(ba_sd), num(ba_beta), num(ba_beta_sd));
    catch err
      % After long runs every slope's unnormalised pdf underflows to zero and Psychtoolbox fails.
      out{end+1} = sprintf('"beta_analysis_error":%s', str(err.message));
    end
  end
  [msg, id] = lastwarn();
  out{end+1} = sprintf('"last_warning":%s', str(msg));
end

% QuestBetaAnalysis returns only 1/iBetaMean and prints t, sd, beta and betaSd with 2 decimals.
% To record all four at full precision, the real QuestBetaAnalysis.m is copied to a temporary
% directory with only its print format widened (%.17g); its arithmetic is untouched.
function [t, sd, beta, beta_sd] = beta_analysis_values(q)
  f = tempname();
  fid = fopen(f, 'w');
  beta = QuestBetaAnalysisWide(q, fid);
  fclose(fid);
  lines = strsplit(strtrim(fileread(f)), "\n");
  delete(f);
  values = sscanf(strrep(lines{end}, 'NaN', 'NaN '), '%f');
  if numel(values) < 4
    t = NaN; sd = NaN; beta_sd = NaN;
  else
    t = values(1); sd = values(2); beta_sd = values(4);
  end
end

function install_wide_beta_analysis(dir)
  src = fileread('/usr/share/psychtoolbox-3/Quest/QuestBetaAnalysis.m');
  old = sprintf('%%5.2f\t%%5.2f\t%%4.1f\t%%4.1f\t%%6.3f\\n');
  wide = sprintf('%%.17g\t%%.17g\t%%.17g\t%%.17g\t%%.17g\\n');
  if isempty(strfind(src, old))
    error('QuestBetaAnalysis.m print format not found; update install_wide_beta_analysis');
  end
  src = strrep(src, old, wide);
  src = strrep(src, 'function betaEstimate=QuestBetaAnalysis(q,fid)', 'function betaEstimate=QuestBetaAnalysisWide(q,fid)');
  fid = fopen(fullfile(dir, 'QuestBetaAnalysisWide.m'), 'w');
  fprintf(fid, '%s', src);
  fclose(fid);
end

function s = params_json(c)
  if isempty(c.range), range = 'null'; else, range = num(c.range); end
  s = sprintf(['"tGuess":%s,"tGuessSd":%s,"pThreshold":%s,"beta":%s,"delta":%s,"gamma":%s,' ...
               '"grain":%s,"range":%s'], num(c.tGuess), num(c.tGuessSd), num(c.pThreshold), num(c.beta), ...
              num(c.delta), num(c.gamma), num(c.grain), range);
end

function c = base_case(name)
  c = struct('name', name, 'tGuess', 0, 'tGuessSd', 2, 'pThreshold', 0.82, 'beta', 3.5, 'delta', 0.01, ...
             'gamma', 0.5, 'grain', 0.01, 'range', [], 'intensities', [], 'responses', [], 'placement', 'quantile', ...
             'first', [], 'trials', 0, 'checkpoint_every', 0, 'store_intensities', true, 'beta_analysis', true, ...
             'simulate_t_actual', []);
end

addpath('/usr/share/psychtoolbox-3/Quest');
wide_dir = tempname(); mkdir(wide_dir); install_wide_beta_analysis(wide_dir); addpath(wide_dir);
warning('off', 'all');  % Psychtoolbox's out-of-range warnings; lastwarn still records them
rand('seed', 20240611);  % QuestSimulate draws from rand

cases = {};

c = base_case('psychopy_reference');
c.tGuess = 50; c.tGuessSd = 50; c.range = 100; c.first = 50;
c.responses = [1 1 0 0 1 1 0 0 1 1]; c.trials = 10;
cases{end+1} = c;

c = base_case('default_dim_quantile_40');
c.tGuess = -0.54; c.tGuessSd = 0.5; c.trials = 40; c.simulate_t_actual = -0.7;
cases{end+1} = c;

c = base_case('mean_placement_40');
c.tGuess = -0.54; c.tGuessSd = 0.5; c.trials = 40; c.placement = 'mean'; c.simulate_t_actual = -0.3;
cases{end+1} = c;

c = base_case('mode_placement_first_40');
c.tGuess = -0.54; c.tGuessSd = 0.5; c.trials = 40; c.placement = 'mode'; c.first = 0.2; c.simulate_t_actual = -0.9;
cases{end+1} = c;

% Intensities beyond the table edges (dim 100 at grain .01: tGuess +- 0.5), huge and infinite ones,
% and values that sit exactly half a grain between steps (MATLAB rounds half away from zero).
c = base_case('out_of_range_intensities');
c.range = 1; c.tGuessSd = 0.4;
c.intensities = [0 0.5 0.505 0.5049 -0.5 -0.505 3 -3 1e12 -1e12 Inf -Inf 0.2 0.125 -0.125 0.375];
c.responses = [1 1 0 1 0 0 1 0 1 0 1 0 1 1 0 1]; c.trials = numel(c.intensities);
cases{end+1} = c;

c = base_case('half_grain_rounding');
c.grain = 0.25; c.range = 4; c.tGuessSd = 1;
c.intensities = [0.125 -0.125 0.375 -0.375 0.625 -0.625 1.125 0.875];
c.responses = [1 0 1 0 1 0 1 1]; c.trials = numel(c.intensities);
cases{end+1} = c;

c = base_case('gamma_above_pthreshold');
c.gamma = 0.9; c.tGuessSd = 1; c.trials = 20; c.simulate_t_actual = 0.3;
cases{end+1} = c;

c = base_case('flat_prior');
c.tGuessSd = Inf; c.range = 4; c.grain = 0.02; c.trials = 30; c.simulate_t_actual = 0.8;
cases{end+1} = c;

c = base_case('four_afc_odd_range');
c.pThreshold = 0.75; c.beta = 2; c.delta = 0; c.gamma = 0.25; c.grain = 0.05; c.range = 6.03;
c.tGuess = 1.5; c.tGuessSd = 1; c.trials = 30; c.simulate_t_actual = 1.1;
cases{end+1} = c;

c = base_case('yes_no');
c.pThreshold = 0.5; c.beta = 2.5; c.delta = 0.02; c.gamma = 0; c.tGuess = -1; c.tGuessSd = 1.5;
c.trials = 30; c.simulate_t_actual = -1.4;
cases{end+1} = c;

c = base_case('long_300_beta_analysis');
c.tGuess = -0.54; c.tGuessSd = 0.5; c.trials = 300; c.simulate_t_actual = -0.6; c.checkpoint_every = 50;
c.store_intensities = false;
cases{end+1} = c;

c = base_case('long_10000');
c.tGuess = -0.54; c.tGuessSd = 0.5; c.trials = 10000; c.simulate_t_actual = -0.6; c.checkpoint_every = 1000;
c.store_intensities = false;
cases{end+1} = c;

entries = {};
for i = 1:numel(cases)
  c = cases{i};
  printf('%s ...\n', c.name); fflush(stdout);
  [out, c] = run_case(c);
  given = '';
  if ~isempty(c.intensities)
    given = sprintf(',"intensities":%s', nums(c.intensities));
  end
  if isempty(c.first), first = 'null'; else, first = num(c.first); end
  responses = sprintf('%d', c.responses);
  entries{end+1} = sprintf('{"name":%s,"params":{%s},"placement":%s,"first":%s%s,"responses":"%s",%s}', ...
    str(c.name), params_json(c), str(c.placement), first, given, responses, strjoin(out, ','));
end

% Parameters Psychtoolbox rejects, with its messages.
errors = {};
bad = {
  'pthreshold_outside_table', @() QuestCreate(0, 1, 0.999, 3.5, 0.01, 0.5);
  'range_zero', @() QuestCreate(0, 1, 0.82, 3.5, 0.01, 0.5, 0.01, 0);
  'range_negative', @() QuestCreate(0, 1, 0.82, 3.5, 0.01, 0.5, 0.01, -2);
  'tguess_nan', @() QuestCreate(NaN, 1, 0.82, 3.5, 0.01, 0.5);
  'tguess_inf', @() QuestCreate(Inf, 1, 0.82, 3.5, 0.01, 0.5);
  'gamma_above_pthreshold_still_omits', @() QuestCreate(0, 1, 0.4, 3.5, 0.01, 0.6);
  'quantile_order_above_one', @() QuestQuantile(QuestCreate(0, 1, 0.82, 3.5, 0.01, 0.5), 1.5);
  'response_two', @() QuestUpdate(QuestCreate(0, 1, 0.82, 3.5, 0.01, 0.5), 0, 2);
};
for i = 1:rows(bad)
  try
    bad{i, 2}();
    msg = '';
  catch err
    msg = err.message;
  end
  errors{end+1} = sprintf('{"name":%s,"message":%s}', str(bad{i, 1}), str(msg));
end

here = fileparts(mfilename('fullpath'));
target = fullfile(here, '..', '..', 'tests', 'study', 'fixtures', 'quest_psychtoolbox.json');
fid = fopen(target, 'w');
fprintf(fid, '{"generator":"scripts/quest_reference/generate_quest_fixtures.m","psychtoolbox":"%s","octave":"%s",\n', ...
        'octave-psychtoolbox-3 3.0.18.12', OCTAVE_VERSION);
fprintf(fid, '"cases":[\n%s\n],\n"errors":[\n%s\n]}\n', strjoin(entries, ",\n"), strjoin(errors, ",\n"));
fclose(fid);
printf('wrote %s\n', target);
