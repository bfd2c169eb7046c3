/*
 * cmd.h - the command table, for the help panel and completion.
 * cmd_exec() itself is declared in ed.h with the state it works on.
 */
#ifndef SG_ED_CMD_H
#define SG_ED_CMD_H

int cmd_count(void);
const char *cmd_name(int i);
const char *cmd_usage(int i);
const char *cmd_help(int i);

#endif
