/**
 * The Plan shows two delays; each says which it is. The planner's schedule
 * delay (modd_plan: |period asked − buffer size × publisher period|) and the
 * link budget's delay on the link (modd_plan.linkbudget: waiting for the
 * packet, then air time) are different figures of different causes.
 */
export const SCHEDULE_DELAY_HELP = "How far each subscriber's delivery period is from the one it asked: "
  + "|period asked − buffer size × publisher period| (the planner's schedule; the link's own delay is apart)";

export const LINK_DELAY_HELP = "How long a subscriber's value takes on this link once its slot is due: "
  + "waiting for the packet it goes in, then its bytes at the link's rate";
