-- Drives `dura lsp` from a headless Neovim (0.7 or later), as a user would: it opens the
-- use case's files in the editor set up by the documented snippet (loaded before this
-- file), makes mistakes, asks for hover, definition, references, completion, formatting
-- and a quick fix, and writes what the editor got to $DURA_NVIM_OUT as JSON.
-- Positions are the editor's own: lines from 0, columns in bytes.

local got = { log = {} }
local published = {} -- publishDiagnostics received, by URI
local WAIT = 60000 -- ms: a loaded machine is slow, never wrong

local on_publish = vim.lsp.handlers["textDocument/publishDiagnostics"]
vim.lsp.handlers["textDocument/publishDiagnostics"] = function(err, result, ctx, config)
  on_publish(err, result, ctx, config)
  published[result.uri] = (published[result.uri] or 0) + 1
end
for _, method in ipairs({ "window/logMessage", "window/showMessage" }) do
  vim.lsp.handlers[method] = function(_, result)
    table.insert(got.log, result.message)
  end
end

local function open(path)
  vim.cmd("edit " .. vim.fn.fnameescape(path))
  local buf = vim.api.nvim_get_current_buf()
  vim.wait(WAIT, function()
    return #vim.lsp.buf_get_clients(buf) > 0
  end, 20)
  return buf
end

-- The diagnostics of a buffer after its next check, once `wanted` holds.
local function diagnostics(buf, wanted)
  local uri = vim.uri_from_bufnr(buf)
  local before = published[uri] or 0
  vim.wait(WAIT, function()
    return (published[uri] or 0) > before and wanted(vim.diagnostic.get(buf))
  end, 20)
  local shown = {}
  for _, d in ipairs(vim.diagnostic.get(buf)) do
    table.insert(shown, {
      lnum = d.lnum,
      col = d.col,
      end_lnum = d.end_lnum,
      end_col = d.end_col,
      message = d.message,
      severity = d.severity,
    })
  end
  return shown
end

-- Put the cursor `inside` bytes into the `nth` line (default: the first) holding `text`.
local function cursor(buf, text, inside, nth)
  vim.api.nvim_set_current_buf(buf)
  local seen = 0
  for i, line in ipairs(vim.api.nvim_buf_get_lines(buf, 0, -1, false)) do
    local at = line:find(text, 1, true)
    if at then
      seen = seen + 1
      if seen == (nth or 1) then
        vim.api.nvim_win_set_cursor(0, { i, at - 1 + (inside or 0) })
        return i - 1
      end
    end
  end
  error("no line holds " .. text)
end

local function request(buf, method, params)
  local answers, err = vim.lsp.buf_request_sync(buf, method, params, WAIT)
  if not answers then
    error(method .. ": " .. tostring(err))
  end
  for _, answer in pairs(answers) do
    if answer.err then
      error(method .. ": " .. vim.inspect(answer.err))
    end
    return answer.result
  end
end

local function replace(buf, line, from, to, text)
  vim.api.nvim_buf_set_text(buf, line, from, line, to, { text })
end

local function run()
  local problem = open(vim.env.DURA_PROBLEM) -- written with a mistake
  got.problem = diagnostics(problem, function(d)
    return #d > 0
  end)
  local robot = open(vim.env.DURA_ROBOT)
  got.robot_opened = diagnostics(robot, function()
    return true
  end)

  -- A typo typed in robot.yaml after an emoji, sent as the small change the editor makes.
  local line = cursor(robot, "📷")
  local text = vim.api.nvim_buf_get_lines(robot, line, line + 1, false)[1]
  local from = text:find("laser_scan", 1, true) - 1
  replace(robot, line, from, from + #"laser_scan", "laser_scna")
  got.robot_typo = diagnostics(robot, function(d)
    return #d > 0
  end)

  -- Its quick fix, applied as the editor applies a code action.
  cursor(robot, "laser_scna", 2)
  local client = vim.lsp.get_active_clients()[1]
  local params = vim.lsp.util.make_range_params(0, client.offset_encoding)
  params.context = { diagnostics = vim.lsp.diagnostic.get_line_diagnostics(robot) }
  local actions = request(robot, "textDocument/codeAction", params) or {}
  got.code_actions = {}
  for _, action in ipairs(actions) do
    table.insert(got.code_actions, action.title)
  end
  vim.lsp.util.apply_workspace_edit(actions[1].edit, client.offset_encoding)
  got.fixed_line = vim.api.nvim_buf_get_lines(robot, line, line + 1, false)[1]
  got.robot_fixed = diagnostics(robot, function(d)
    return #d == 0
  end)

  -- Hover on an action in the domain, opened from the task that names it.
  cursor(robot, "take_picture:", 3, 2) -- the task, not the behavior
  local definition = request(robot, "textDocument/definition", vim.lsp.util.make_position_params())
  got.definition = definition
  vim.lsp.util.jump_to_location(definition[1], client.offset_encoding)
  local domain = vim.api.nvim_get_current_buf()
  got.jumped = {
    file = vim.fn.fnamemodify(vim.api.nvim_buf_get_name(domain), ":t"),
    cursor = vim.api.nvim_win_get_cursor(0),
  }
  vim.wait(WAIT, function()
    return #vim.lsp.buf_get_clients(domain) > 0
  end, 20)
  local hover = request(domain, "textDocument/hover", vim.lsp.util.make_position_params())
  got.hover = hover and hover.contents.value

  cursor(domain, "(robot_at ?p - place)", 2)
  local params = vim.lsp.util.make_position_params()
  params.context = { includeDeclaration = true }
  got.references = #(request(domain, "textDocument/references", params) or {})

  cursor(domain, "(robot_at ?from))", 1)
  local completion = request(domain, "textDocument/completion", vim.lsp.util.make_position_params())
  got.completion = {}
  for _, item in ipairs(completion.items or completion) do
    table.insert(got.completion, item.label)
  end

  -- Formatting undoes a line's lost indentation and changes nothing else.
  local written = vim.api.nvim_buf_get_lines(domain, 0, -1, false)
  line = cursor(domain, ":parameters (?from ?to - place)")
  replace(domain, line, 0, 4, "")
  vim.lsp.buf.formatting_sync(nil, WAIT)
  got.formatted_as_written = vim.deep_equal(written, vim.api.nvim_buf_get_lines(domain, 0, -1, false))
end

local function finish()
  local ok, err = pcall(run)
  if not ok then
    got.error = tostring(err)
  end
  vim.fn.writefile({ vim.fn.json_encode(got) }, vim.env.DURA_NVIM_OUT)
  vim.lsp.stop_client(vim.lsp.get_active_clients())
  vim.wait(10000, function()
    return #vim.lsp.get_active_clients() == 0
  end, 50)
  vim.cmd("qall!")
end

vim.api.nvim_create_autocmd("VimEnter", { callback = finish, nested = true })
