/** One label / value pair of a definition list (`<dl>`), the value in tabular figures. */
export function Row({ label, value, testId }: { label: string; value: string; testId?: string }) {
  return (
    <>
      <dt>{label}</dt>
      <dd className="num" data-testid={testId}>
        {value}
      </dd>
    </>
  );
}
