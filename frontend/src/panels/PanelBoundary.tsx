/**
 * Every panel renders inside one of these: a failure stays in the panel (with
 * its message and a retry), and a lazy panel shows a loading state. A failed
 * panel tries again by itself every ``retryMs`` (3 s), so it comes back once
 * the data that broke it is good again, without a click.
 */
import { Component, Suspense, type ErrorInfo, type ReactNode } from "react";

interface Props { title: string; children: ReactNode; retryMs?: number }
interface State { error: Error | null }

/** How long a failed panel waits before it renders again by itself. */
export const PANEL_RETRY_MS = 3000;

export class PanelBoundary extends Component<Props, State> {
  state: State = { error: null };
  private timer: ReturnType<typeof setTimeout> | null = null;

  static getDerivedStateFromError(error: Error): State {
    return { error };
  }

  componentDidCatch(_error: Error, _info: ErrorInfo): void {
    this.clearTimer();
    this.timer = setTimeout(() => { this.timer = null; this.setState({ error: null }); },
      this.props.retryMs ?? PANEL_RETRY_MS);
  }

  componentWillUnmount(): void {
    this.clearTimer();
  }

  private clearTimer(): void {
    if (this.timer !== null) clearTimeout(this.timer);
    this.timer = null;
  }

  private retry = (): void => {
    this.clearTimer();
    this.setState({ error: null });
  };

  render() {
    if (this.state.error) {
      const seconds = Math.round((this.props.retryMs ?? PANEL_RETRY_MS) / 1000);
      return (
        <div className="panel-error" role="alert">
          <strong>The {this.props.title} panel failed.</strong>
          <pre>{this.state.error.message}</pre>
          <p className="muted">It tries again by itself every {seconds} s.</p>
          <button onClick={this.retry}>Retry</button>
        </div>
      );
    }
    return <Suspense fallback={<div className="panel-loading" role="status">Loading {this.props.title}…</div>}>{this.props.children}</Suspense>;
  }
}
